"""Aggregates → a shaded scene: world meshes, curvature, materials, CDRF vertex colours and σ — SPEC §4.

All element meshes are concatenated so normals and curvature come from one libigl call (elements
are disjoint components, so this equals per-element evaluation), shaded in one vectorised pass,
then split back into one mesh per element part (ikura: membrane, yolk; fish: flesh, fat).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from nodegraph.codec import derived
from nodegraph.values import Mesh

from ..values import Aggregate, Material, ShadedScene
from . import materials as mat
from .cdrf import CdrfTable, curvature_sigma
from .curvature import normals_and_curvature
from .vertex_shading import Light, cdrf_colors


@dataclass(frozen=True)
class ShadeSettings:
    rice: Material | None  # the cooked material's optics; None: no material wired (then no rice may be shaded)
    sigma0: float
    lights: list[Light]
    ambient: float
    presets: dict[str, str]
    syrup_color: tuple[float, float, float]
    syrup_depth: float
    syrup_spread: float
    syrup_levels: int
    syrup_runs: int
    syrup_run_length: float
    seed: int  # draws the syrup's runs (``materials.syrup_runs``) and each egg's tint (``egg_tints``)
    scenery_color: tuple[float, float, float]
    scenery_roughness: float
    table: CdrfTable
    egg_tints: int = mat.EGG_TINTS  # membrane tints the eggs are drawn from (``materials.ikura_tints``)
    key_gain: float = 1.0  # the preview's key softbox over its default (``ShadedScene.key_gain``)


@dataclass
class _Piece:
    mesh: Mesh  # world-space mesh of one element part (or one scenery mesh)
    material: Material
    transmittance: np.ndarray | None = None  # per vertex, where it varies over the skin (``eye_transmittance``)


def _materials(settings: ShadeSettings) -> dict[str, tuple[Material, ...]]:
    """Each preset's materials: one for a plain solid, one per part (``materials.PARTS``), one per syrup grade."""
    ice, syrup = mat.ice_materials(settings.syrup_color)
    return {
        "rice": (settings.rice,),
        "chestnut": (mat.chestnut_material(),),
        "ikura": mat.ikura_materials(),
        "ikura_tints": mat.ikura_tints(settings.egg_tints),
        "salmon": mat.fish_materials("salmon"),
        "tuna": mat.fish_materials("tuna"),
        "ice": mat.syrup_grades(ice, syrup, settings.syrup_levels),
    }


def _element_pieces(
    aggregate: Aggregate, settings: ShadeSettings, materials: dict[str, tuple[Material, ...]], numbers: dict[str, int]
) -> list[_Piece]:
    """The aggregate's element parts with their materials, named ``<kind>/<number>[/<part>]``, numbered per
    kind across the scene's aggregates (``numbers``: the next number of each kind). Ice gets the syrup grade
    of its depth below the aggregate's top surface (``materials.soak_depths``, ``materials.syrup_levels``), deeper
    where a run of syrup goes down the flank (``materials.syrup_runs``)."""
    p = aggregate.placement
    kinds = [lib.kind for lib in aggregate.libraries]
    presets = [mat.preset_for_kind(kind, settings.presets) for kind in kinds]
    meshes = derived(aggregate, "element_shapes", _element_shapes)
    is_ice = np.array([presets[k] == "ice" for k in p.kinds], bool)
    grade = np.zeros(len(p), np.int64)
    if is_ice.any():
        ice_vertices = [meshes[i].vertices for i in np.flatnonzero(is_ice)]
        cell = float(np.median([np.ptp(v, axis=0).max() for v in ice_vertices]))  # one element length
        depths = mat.soak_depths(ice_vertices, cell, settings.syrup_spread)
        tops = np.array([v[np.argmax(v[:, 2])] for v in ice_vertices])
        rng = np.random.default_rng(settings.seed)
        limits = mat.syrup_runs(tops, settings.syrup_depth, settings.syrup_runs, settings.syrup_run_length, cell, rng)
        grade[is_ice] = mat.syrup_levels(depths, limits, settings.syrup_levels)
    is_egg = np.array([presets[k] == "ikura" for k in p.kinds], bool)
    tint = np.zeros(len(p), np.int64)
    if is_egg.any():
        tint[is_egg] = egg_tints(p.positions[is_egg], len(materials["ikura_tints"]), settings.seed)
    rice = [k for k in np.unique(p.kinds) if presets[k] == "rice"]
    if settings.rice is None and rice:
        kind = kinds[rice[0]]
        raise ValueError(
            f"element kind '{kind}' is shaded as rice, whose water content and optics are the cooked material's: "
            "wire a cooked_rice node into input 'material' (the one the xpbd node reads)"
        )
    pieces = []
    splits: dict[tuple[int, int], list[tuple[int, np.ndarray, np.ndarray]]] = {}  # per (kind, variant): see _parts
    for i in range(len(p)):
        preset = presets[p.kinds[i]]
        kind = kinds[p.kinds[i]]
        numbers[kind] = numbers.get(kind, -1) + 1
        mesh = dataclasses.replace(meshes[i], name=f"{kind}/{numbers[kind]:04d}")
        if preset == "ice":
            pieces.append(_Piece(mesh, materials["ice"][grade[i]]))
        elif preset not in mat.PARTS:
            pieces.append(_Piece(mesh, materials[preset][0]))
        else:
            names = mat.PARTS[preset]
            key = (int(p.kinds[i]), int(p.variants[i]) % len(aggregate.libraries[p.kinds[i]]))
            if key not in splits:
                splits[key] = _parts(mesh, names, f"element {i} ({kind})", preset)
            by_part = {part: mesh.vertices[used] for part, used, _ in splits[key]}
            if preset == "ikura" and 0 in by_part and 1 in by_part:  # the oil floats up, whatever the egg's turn
                by_part[1] = floated_droplet(by_part[0], by_part[1])
            for part, _, faces in splits[key]:
                material, tint_of = materials[preset][part], None
                if preset == "ikura" and part == 0:  # the membrane: the egg's own tint, paler over its eye
                    material = materials["ikura_tints"][tint[i]]
                    if 1 in by_part:
                        tint_of = eye_transmittance(by_part[0], by_part[1], material.subsurface_color)
                pieces.append(_Piece(Mesh(by_part[part], faces, name=f"{mesh.name}/{names[part]}"), material, tint_of))
    return pieces


def _element_shapes(aggregate: Aggregate) -> list[Mesh]:
    """Each element's world mesh without normals: the scene's normals come from ``normals_and_curvature``."""
    shapes = aggregate.without_normals()
    return [shapes.element_mesh(i) for i in range(len(aggregate.placement))]


EGG_NEIGHBOURS = 1.3  # eggs nearer than this many median egg spacings are neighbours (``egg_tints``)


def egg_tints(centres: np.ndarray, count: int, seed: int) -> np.ndarray:
    """Each egg's membrane tint (0 … ``count`` − 1), drawn from ``seed`` so that no two touching eggs share one
    where ``count`` allows: the eggs in a random order (seeded), each drawing among the tints its neighbours
    (centres nearer than ``EGG_NEIGHBOURS`` median nearest-neighbour spacings) do not have yet."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng([seed, 48])  # its own stream: the syrup's runs draw from the seed alone
    n = len(centres)
    out = np.full(n, -1, np.int64)
    if count <= 1 or n == 0:
        return np.zeros(n, np.int64)
    tree = cKDTree(centres)
    spacing = float(np.median(tree.query(centres, k=2)[0][:, 1])) if n > 1 else 1.0
    neighbours = tree.query_ball_point(centres, EGG_NEIGHBOURS * spacing)
    for i in rng.permutation(n):
        taken = {int(out[j]) for j in neighbours[i] if out[j] >= 0}
        free = [t for t in range(count) if t not in taken] or list(range(count))
        out[i] = free[int(rng.integers(len(free)))]
    return out


DROPLET_CLEARANCE = 0.05  # mm: the floated droplet keeps at least this much fluid under every part of the membrane


def floated_droplet(skin: np.ndarray, droplet: np.ndarray) -> np.ndarray:
    """An egg's oil droplet (``droplet``, its vertices inside the membrane ``skin``) moved, without turning, so that
    it sits as far from the egg's centre as before but straight above it (world +z). The droplet is the egg's
    oil, lighter than the fluid around it (fish oil: specific gravity 0.928, FAO; the egg 1.03 g/cm³, docs/sizes.md),
    so it floats to the top of the egg however the egg came to rest: the library places it along the egg's own
    +z (``base_mesh.eye_gap``) and the placement turns each egg at random, which pointed half the eyes into the
    rice, away from the camera (issue 48: "the egg eye is not visible"). Where an egg is dented (a neighbour
    pressed on its top, ``deform_contacts``) the lift shrinks until the droplet keeps ``DROPLET_CLEARANCE`` of
    fluid under the skin everywhere (the skin as a star-shaped surface about its centre)."""
    from scipy.spatial import cKDTree

    skin, droplet = np.asarray(skin, np.float64), np.asarray(droplet, np.float64)
    centre, middle = skin.mean(axis=0), droplet.mean(axis=0)
    lift = float(np.linalg.norm(middle - centre))
    if lift <= 1e-9:
        return droplet
    rel = skin - centre
    reach = np.linalg.norm(rel, axis=1)
    tree = cKDTree(rel / np.maximum(reach, 1e-12)[:, None])

    def fits(height: float) -> bool:
        moved = droplet - middle + centre + np.array([0.0, 0.0, height])
        out = moved - centre
        distance = np.linalg.norm(out, axis=1)
        _, nearest = tree.query(out / np.maximum(distance, 1e-12)[:, None])
        return bool((distance <= reach[nearest] - DROPLET_CLEARANCE).all())

    low, high = 0.0, lift
    if not fits(high):
        for _ in range(12):  # bisect for the highest lift that fits
            mid = 0.5 * (low + high)
            low, high = (mid, high) if fits(mid) else (low, mid)
        high = low
    return droplet - middle + centre + np.array([0.0, 0.0, high])


def eye_transmittance(skin: np.ndarray, droplet: np.ndarray, color) -> np.ndarray:
    """Per vertex of an egg's membrane (``skin``, around the oil droplet's vertices ``droplet``): the colour light
    keeps through the egg there, in and out: ``color`` (the whole egg's) to the power of the fluid's depth under that
    vertex, its distance to the droplet's surface, as a share of that depth with the droplet at the egg's centre
    (Beer–Lambert over the fluid; 1 at most). The droplet floats ``base_mesh.eye_gap`` under the skin (G eq. 10's
    yolk, lighter than the fluid), so the skin over it is paler, most at the eye's centre and fading to the egg's
    colour about a droplet's radius away: the eye is the droplet seen through a thinning fluid, a soft paler patch,
    with no edge of its own. A concentric droplet leaves the egg its colour everywhere."""
    skin, droplet = np.asarray(skin, np.float64), np.asarray(droplet, np.float64)
    centre, middle = skin.mean(axis=0), droplet.mean(axis=0)
    radius = float(np.linalg.norm(skin - centre, axis=1).mean())
    r_o = float(np.linalg.norm(droplet - middle, axis=1).mean())
    depth = np.linalg.norm(skin - middle, axis=1) - r_o
    share = np.clip(depth / max(radius - r_o, 1e-9), 0.0, 1.0)
    return np.clip(np.asarray(color, np.float64), 0.0, 1.0)[None, :] ** share[:, None]


def _parts(mesh: Mesh, names: tuple[str, ...], what: str, preset: str) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """(part, the vertices it uses, its faces renumbered to them) per face part: the same for every element of a
    library mesh (its faces and parts), so found once per variant, not per element."""
    parts = np.zeros(len(mesh.faces), np.int32) if mesh.parts is None else mesh.parts
    out = []
    for part in np.unique(parts):
        if not 0 <= part < len(names):
            allowed = ", ".join(f"{k} {name}" for k, name in enumerate(names))
            raise ValueError(f"{what}: face part {part} is not a {preset} part ({allowed})")
        used, inverse = np.unique(mesh.faces[parts == part], return_inverse=True)
        out.append((int(part), used, inverse.reshape(-1, 3)))
    return out


def shade_scene(
    aggregates: list[Aggregate], scenery: list[Mesh], settings: ShadeSettings, filling: list[Mesh] | None = None
) -> ShadedScene:
    """CDRF-shaded meshes, one per element part and scenery mesh, with their materials. ``filling``: closed meshes
    of rice under the simulated grains (the shade node's input), in the cooked rice's material: a bowl of rice is
    rice to its floor, and where the top layer (two grains deep) leaves a gap, the gap shows more rice, lit through
    the grains round it; without it the gaps showed the dark glaze of the bowl's floor as black holes (issue 48)."""
    numbers: dict[str, int] = {}
    materials = _materials(settings)
    pieces = [piece for a in aggregates for piece in _element_pieces(a, settings, materials, numbers)]
    if not pieces:
        raise ValueError("aggregates: no elements to shade (every aggregate is empty)")
    from ..shapes.chopsticks import NAME as CHOPSTICKS

    looks = {mat.NORI: mat.nori_material(), CHOPSTICKS: mat.lacquer_material()}
    ceramic = mat.ceramic_material(settings.scenery_color, settings.scenery_roughness)
    pieces += [
        _Piece(Mesh(m.vertices, m.faces, name=m.name or f"scenery_{k}"), looks.get(m.name, ceramic))
        for k, m in enumerate(scenery)
        if len(m.faces)
    ]
    rice = materials["rice"][0]
    if filling and rice is None:
        raise ValueError(
            "shade: input 'filling' is shown in the cooked rice's material: wire a cooked_rice node into 'material'"
        )
    pieces += [
        _Piece(Mesh(m.vertices, m.faces, name=f"rice_fill_{k}"), rice)
        for k, m in enumerate(filling or [])
        if len(m.faces)
    ]

    counts = np.array([len(piece.mesh.vertices) for piece in pieces])
    starts = np.concatenate([[0], np.cumsum(counts)])
    vertices = np.concatenate([piece.mesh.vertices for piece in pieces])
    faces = np.concatenate([piece.mesh.faces + starts[k] for k, piece in enumerate(pieces)])
    normals, curvature = normals_and_curvature(vertices, faces)

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
    tints = ()
    if any(piece.transmittance is not None for piece in pieces):
        tints = tuple(np.zeros((0, 3)) if p.transmittance is None else p.transmittance for p in pieces)
    return ShadedScene(
        tuple(meshes),
        tuple(materials),
        np.array(material_of, np.int32),
        cdrf_sigma=sigmas,
        transmittance=tints,
        key_gain=settings.key_gain,
    )
