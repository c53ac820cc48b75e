"""Aggregates → a shaded scene: world meshes, curvature, materials, CDRF vertex colours and σ — SPEC §4.

All element meshes are concatenated so normals and curvature come from one libigl call (elements
are disjoint components, so this equals per-element evaluation), shaded in one vectorised pass,
then split back into one mesh per element part (ikura: membrane, yolk).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from nodegraph.values import Mesh

from ..values import Aggregate, Material, ShadedScene
from . import materials as mat
from .cdrf import CdrfTable, curvature_sigma
from .curvature import mean_curvature, vertex_normals
from .vertex_shading import Light, cdrf_colors

PART_NAMES = {0: "membrane", 1: "yolk"}


@dataclass(frozen=True)
class ShadeSettings:
    water_content: float
    sigma0: float
    lights: list[Light]
    ambient: float
    presets: dict[str, str]
    syrup_color: tuple[float, float, float]
    syrup_coverage: float
    scenery_color: tuple[float, float, float]
    table: CdrfTable


@dataclass
class _Piece:
    mesh: Mesh  # world-space mesh of one element part (or one scenery mesh)
    material: Material


def _element_pieces(aggregate: Aggregate, settings: ShadeSettings, numbers: dict[str, int]) -> list[_Piece]:
    """The aggregate's element parts with their materials, named ``<kind>/<number>[/<part>]``, numbered per
    kind across the scene's aggregates (``numbers``: the next number of each kind)."""
    p = aggregate.placement
    kinds = [lib.kind for lib in aggregate.libraries]
    presets = [mat.preset_for_kind(kind, settings.presets) for kind in kinds]
    is_ice = np.array([presets[k] == "ice" for k in p.kinds], bool)
    syrup = np.zeros(len(p), bool)
    syrup[is_ice] = mat.syrup_mask(p.positions[is_ice, 2], settings.syrup_coverage)
    rice = mat.rice_material(settings.water_content)
    ikura = mat.ikura_materials()
    ice = mat.ice_materials(settings.syrup_color)
    pieces = []
    for i in range(len(p)):
        preset = presets[p.kinds[i]]
        kind = kinds[p.kinds[i]]
        numbers[kind] = numbers.get(kind, -1) + 1
        mesh = dataclasses.replace(aggregate.element_mesh(i), name=f"{kind}/{numbers[kind]:04d}")
        if preset == "rice":
            pieces.append(_Piece(mesh, rice))
        elif preset == "ice":
            pieces.append(_Piece(mesh, ice[int(syrup[i])]))
        else:
            parts = np.zeros(len(mesh.faces), np.int32) if mesh.parts is None else mesh.parts
            for part in np.unique(parts):
                if part not in PART_NAMES:
                    raise ValueError(
                        f"element {i} ({kinds[p.kinds[i]]}): face part {part} is not an ikura part (0 membrane, 1 yolk)"
                    )
                pieces.append(_Piece(_submesh(mesh, parts == part, f"{mesh.name}/{PART_NAMES[part]}"), ikura[part]))
    return pieces


def _submesh(mesh: Mesh, face_mask: np.ndarray, name: str) -> Mesh:
    faces = mesh.faces[face_mask]
    used, inverse = np.unique(faces, return_inverse=True)
    return Mesh(mesh.vertices[used], inverse.reshape(-1, 3), name=name)


def shade_scene(aggregates: list[Aggregate], scenery: list[Mesh], settings: ShadeSettings) -> ShadedScene:
    """CDRF-shaded meshes, one per element part and scenery mesh, with their materials."""
    numbers: dict[str, int] = {}
    pieces = [piece for aggregate in aggregates for piece in _element_pieces(aggregate, settings, numbers)]
    if not pieces:
        raise ValueError("aggregates: no elements to shade (every aggregate is empty)")
    ceramic = mat.ceramic_material(settings.scenery_color)
    pieces += [
        _Piece(Mesh(m.vertices, m.faces, name=m.name or f"scenery_{k}"), ceramic)
        for k, m in enumerate(scenery)
        if len(m.faces)
    ]

    counts = np.array([len(piece.mesh.vertices) for piece in pieces])
    starts = np.concatenate([[0], np.cumsum(counts)])
    vertices = np.concatenate([piece.mesh.vertices for piece in pieces])
    faces = np.concatenate([piece.mesh.faces + starts[k] for k, piece in enumerate(pieces)])
    normals = vertex_normals(vertices, faces)
    curvature = mean_curvature(vertices, faces, normals)

    per_vertex = lambda field: np.repeat(np.array([getattr(piece.material, field) for piece in pieces]), counts, axis=0)
    colors = cdrf_colors(
        normals,
        curvature,
        per_vertex("base_color"),
        per_vertex("subsurface_color"),
        per_vertex("subsurface"),
        settings.sigma0,
        settings.lights,
        settings.ambient,
        settings.table,
    ).astype(np.float32)
    sigma = curvature_sigma(curvature, settings.sigma0).astype(np.float32)

    materials: list[Material] = []
    material_of = []
    meshes = []
    for k, piece in enumerate(pieces):
        if piece.material not in materials:
            materials.append(piece.material)
        material_of.append(materials.index(piece.material))
        rows = slice(starts[k], starts[k + 1])
        meshes.append(
            Mesh(
                piece.mesh.vertices,
                piece.mesh.faces,
                normals=normals[rows],
                colors=colors[rows],
                parts=piece.mesh.parts,
                name=piece.mesh.name,
            )
        )
    sigmas = tuple(sigma[starts[k] : starts[k + 1]] for k in range(len(pieces)))
    return ShadedScene(tuple(meshes), tuple(materials), np.array(material_of, np.int32), cdrf_sigma=sigmas)
