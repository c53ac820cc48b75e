"""A shaded scene as binary glTF 2.0 (.glb) with KHR_materials_* extensions — SPEC §4 output.

Hand-written JSON + one binary buffer because trimesh's exporter (the library at hand) maps
materials to core PBR only and drops transmission, volume, IOR, specular, clearcoat, sheen and emissive
strength. One glTF mesh and node per element part; the root node turns our Z-up millimetres into
glTF's Y-up metres. The materials carry what the preview renders (``mitsuba_scene``): the ikura membrane
as transmission + volume (IOR; the colour light keeps through the element as the base colour), rice as
diffuse transmission (the CDRF's translucency at the material's median curvature) with sheen and clearcoat,
shaved ice as diffuse transmission of its ``subsurface`` (syrup-soaked ice part transmission too, and a coat),
the bowl's glaze as clearcoat.
The CDRF vertex colours are not written (they hold lighting, which a viewer multiplying them into the base colour
would light again); the CDRF's per-vertex σ travels as the custom attribute ``_CDRF_SIGMA`` (rad). ``COLOR_0``
carries only a skin's own transmittance per vertex where it varies (``ShadedScene.transmittance``: an egg's
membrane, paler over its eye): the material's base colour is then the palest it reaches per channel
(``vertex_tints``) and ``COLOR_0`` the share of it each vertex keeps, so that base colour × ``COLOR_0``, what glTF
and Blender's importer make of it, is the vertex's transmittance. Each material's
``extras`` carry its whole principled look (``look.principled_attributes``), which Blender keeps as custom
properties for the add-on in ``blender/nodegraph_import``.
"""

from __future__ import annotations

import json
import struct

import numpy as np

from ..shading.curvature import row_lengths
from ..values import Material, ShadedScene
from .look import PREFIX, exported_base_color, exported_specular, principled_attributes
from .mesh_files import rowwise

FLOAT, UINT = 5126, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
Z_UP_TO_Y_UP = [-np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)]  # quaternion (x, y, z, w): −90° about x
SHEEN_ROUGHNESS = 0.5  # a water film's soft rim (glTF's sheen roughness; Blender principled v1 has none)


def material_json(material: Material, translucency: float = 0.0, base=None) -> tuple[dict, set[str]]:
    """Principled parameters → glTF PBR plus the KHR extensions that carry the rest; ``translucency`` is the
    material's diffuse-transmission weight (``subsurface × cdrf.translucency(σ)`` at its median σ); ``base``: the
    base colour where its meshes carry their own per vertex (``vertex_tints``)."""
    ext: dict[str, dict] = {}
    thickness = float(np.mean(material.subsurface_radius))  # mm, the mesh's units
    volume = {
        "thicknessFactor": thickness,
        "attenuationColor": [float(c) for c in material.subsurface_color],
        "attenuationDistance": max(thickness * 1e-3, 1e-6),  # world units: m
    }
    from ..shading.materials import is_ice

    diffuse = {
        "diffuseTransmissionFactor": float(translucency),
        "diffuseTransmissionColorFactor": [float(c) for c in material.subsurface_color],
    }
    if material.transmission > 0:
        # a volume that refracts; its colour is the base colour (``look.exported_base_color``: what light keeps
        # through the element), no absorption on top: that coloured the light twice (Blender: crimson eggs)
        ext["KHR_materials_transmission"] = {"transmissionFactor": material.transmission}
        ext["KHR_materials_volume"] = {"thicknessFactor": thickness}
        if translucency > 0 and is_ice(material):  # syrup-soaked ice passes most of its diffuse light on too
            ext["KHR_materials_diffuse_transmission"] = diffuse
    elif translucency > 0:
        ext["KHR_materials_diffuse_transmission"] = diffuse
        ext["KHR_materials_volume"] = volume
    if material.ior != 1.5:
        ext["KHR_materials_ior"] = {"ior": material.ior}
    specular = exported_specular(material)  # 0 where the coat is the only skin (``look.coat_is_skin``)
    if specular != 0.5:
        # Blender's convention: specular 0.5 is F0 = 0.04, glTF's default; the factor scales F0.
        ext["KHR_materials_specular"] = {"specularFactor": min(1.0, 2.0 * specular)}
    if material.clearcoat > 0:
        ext["KHR_materials_clearcoat"] = {
            "clearcoatFactor": material.clearcoat,
            "clearcoatRoughnessFactor": material.clearcoat_roughness,
        }
    if material.sheen > 0:
        tint = (1.0 - material.sheen_tint) + material.sheen_tint * np.asarray(material.base_color)
        ext["KHR_materials_sheen"] = {
            "sheenColorFactor": [float(c) for c in np.clip(material.sheen * tint, 0.0, 1.0)],
            "sheenRoughnessFactor": SHEEN_ROUGHNESS,
        }
    out = {
        "name": material.name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [*(exported_base_color(material) if base is None else map(float, base)), 1.0],
            "metallicFactor": material.metallic,
            "roughnessFactor": material.roughness,
        },
    }
    if material.emission_strength > 0 and max(material.emission) > 0:
        out["emissiveFactor"] = list(material.emission)
        if material.emission_strength != 1.0:
            ext["KHR_materials_emissive_strength"] = {"emissiveStrength": material.emission_strength}
    if ext:
        out["extensions"] = ext
    # the whole look under the names the USD file uses, for the Blender add-on (blender/nodegraph_import)
    out["extras"] = {
        PREFIX + k: list(v) if isinstance(v, tuple) else v
        for k, v in principled_attributes(material, translucency).items()
    }
    return out, set(ext)


def material_translucency(scene: ShadedScene) -> list[float]:
    """Per material: its diffuse-transmission weight at the median CDRF σ of its vertices (0 without σ); shaved ice
    (``materials.is_ice``, a thin diffuser) its ``subsurface``, as the preview renders it."""
    from ..shading.cdrf import translucency
    from ..shading.materials import is_ice

    out = []
    for index, material in enumerate(scene.materials):
        if is_ice(material):
            out.append(float(material.subsurface))
            continue
        sigmas = [s for s, k in zip(scene.cdrf_sigma, scene.material_of) if k == index and len(s)]
        if not sigmas or material.subsurface <= 0:
            out.append(0.0)
            continue
        median = float(np.median(np.concatenate(sigmas)))
        out.append(round(float(material.subsurface * translucency(median)), 4))
    return out


def vertex_tints(scene: ShadedScene) -> dict[int, np.ndarray]:
    """Material index → its base colour where its meshes carry their own transmittance per vertex: per channel the
    largest any of its vertices keeps (the material's own for meshes without), so that ``COLOR_0`` = transmittance /
    base colour stays within 0–1, as glTF requires."""
    out: dict[int, np.ndarray] = {}
    for k, index in enumerate(scene.material_of):
        own = scene.vertex_transmittance(k)
        if own is None:
            continue
        peak = np.max(own, axis=0).astype(np.float64)
        out[int(index)] = np.maximum(out.get(int(index), peak), peak)
    for k, index in enumerate(scene.material_of):
        if int(index) in out and scene.vertex_transmittance(k) is None:
            out[int(index)] = np.maximum(out[int(index)], exported_base_color(scene.materials[index]))
    return {index: np.maximum(color, 1e-6) for index, color in out.items()}


class _Buffer:
    """The .glb binary chunk: 4-byte aligned views, one accessor each."""

    def __init__(self):
        self.chunks: list[bytes] = []
        self.size = 0
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def add(self, array: np.ndarray, component: int, kind: str, target: int | None, bounds=None) -> int:
        """A view and an accessor for ``array``; ``target`` None for data no vertex shader reads directly
        (instance transforms); ``bounds``: the (min, max) rows of ``array`` for the accessor (``block_bounds``)."""
        data = np.ascontiguousarray(array).tobytes()
        view = {"buffer": 0, "byteOffset": self.size, "byteLength": len(data)}
        self.views.append(view if target is None else {**view, "target": target})
        self.chunks.append(data)
        self.size += len(data)
        pad = (-self.size) % 4
        if pad:
            self.chunks.append(b"\0" * pad)
            self.size += pad
        accessor = {"bufferView": len(self.views) - 1, "componentType": component, "count": len(array), "type": kind}
        if bounds is not None:
            accessor["min"], accessor["max"] = bounds[0].tolist(), bounds[1].tolist()
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def unit_normals(normals: np.ndarray) -> np.ndarray:
    """float32 unit normals (the validator checks length); a zero normal becomes +z."""
    n = np.asarray(normals, np.float32)
    length = row_lengths(n)
    n = np.where(length > 1e-6, n / np.maximum(length, 1e-12), np.float32([0, 0, 1]))
    return (n / row_lengths(n)).astype(np.float32)


def _mesh_json(
    buffer: _Buffer,
    scene: ShadedScene,
    k: int,
    positions: np.ndarray,
    bounds,
    normals: np.ndarray | None,
    name: str,
    tints: dict[int, np.ndarray],
) -> dict:
    """glTF mesh k of the scene with the given float32 vertex positions (its own, or a prototype's centred ones)
    and their (min, max), and float32 unit normals (None: none); ``tints``: ``vertex_tints``."""
    mesh = scene.meshes[k]
    attributes = {"POSITION": buffer.add(positions, FLOAT, "VEC3", ARRAY_BUFFER, bounds=bounds)}
    if normals is not None:
        attributes["NORMAL"] = buffer.add(normals, FLOAT, "VEC3", ARRAY_BUFFER)
    if scene.cdrf_sigma:
        sigma = np.asarray(scene.cdrf_sigma[k], np.float32)
        attributes["_CDRF_SIGMA"] = buffer.add(sigma, FLOAT, "SCALAR", ARRAY_BUFFER)
    base = tints.get(int(scene.material_of[k]))
    if base is not None:
        own = scene.vertex_transmittance(k)
        own = (
            np.tile(exported_base_color(scene.materials[scene.material_of[k]]), (len(mesh.vertices), 1))
            if own is None
            else own
        )
        attributes["COLOR_0"] = buffer.add(
            np.clip(own / base, 0.0, 1.0).astype(np.float32), FLOAT, "VEC3", ARRAY_BUFFER
        )
    indices = buffer.add(np.asarray(mesh.faces, np.uint32).reshape(-1), UINT, "SCALAR", ELEMENT_ARRAY_BUFFER)
    primitive = {"attributes": attributes, "indices": indices, "material": int(scene.material_of[k]), "mode": 4}
    return {"name": name, "primitives": [primitive]}


def glb_bytes(scene: ShadedScene, instancing: bool = True, groups=None, weights=None) -> bytes:
    """The scene as a .glb (glTF 2.0 binary): JSON chunk + BIN chunk. With ``instancing``, each group of meshes
    that are one mesh moved rigidly (``instancing.instance_groups``) is one mesh that a node per element places
    (translation and rotation) instead of a copy per element. ``groups``
    and ``weights``: the scene's ``instance_groups`` and ``material_translucency`` when already found (the export
    node finds them once for every file it writes)."""
    from .instancing import written_meshes

    buffer = _Buffer()
    materials, used = [], set()
    tints = vertex_tints(scene)
    for index, (material, weight) in enumerate(
        zip(scene.materials, material_translucency(scene) if weights is None else weights)
    ):
        entry, ext = material_json(material, weight, tints.get(index))
        materials.append(entry)
        used |= ext
    out = written_meshes(scene, instancing, groups)
    groups, written = out.prototypes, out.indices
    if not written:
        raise ValueError("scene: no mesh with faces to export")
    with_normals = [k for k in written if scene.meshes[k].normals is not None]
    normals = dict(zip(with_normals, rowwise([scene.meshes[k].normals for k in with_normals], unit_normals)))
    meshes, nodes = [], []
    for k, points, low, high in zip(written, out.positions, out.lows, out.highs):
        name = scene.meshes[k].name or f"mesh_{k}"
        meshes.append(_mesh_json(buffer, scene, k, points, (low, high), normals.get(k), name, tints))
        group = groups.get(k)
        if group is None:
            nodes.append({"name": name, "mesh": len(meshes) - 1})
            continue
        # glTF core instancing (§3.5.1: nodes may share a mesh), one node per element: every reader places
        # them, where EXT_mesh_gpu_instancing is drawn by readers that lack it as one prototype at the origin
        for member, rotation, position in zip(group.members, group.quaternions(), group.positions):
            nodes.append(
                {
                    "name": scene.meshes[int(member)].name or f"mesh_{int(member)}",
                    "mesh": len(meshes) - 1,
                    "rotation": [float(c) for c in rotation],
                    "translation": [float(c) for c in position],
                }
            )
    root = {
        "name": "aggregate",
        "rotation": Z_UP_TO_Y_UP,
        "scale": [1e-3] * 3,  # Z-up mm → Y-up m
        "children": list(range(1, len(nodes) + 1)),
    }
    document = {
        "asset": {"version": "2.0", "generator": "nodegraph export"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [root, *nodes],
        "meshes": meshes,
        "materials": materials,
        "accessors": buffer.accessors,
        "bufferViews": buffer.views,
        "buffers": [{"byteLength": buffer.size}],
    }
    if used:
        document["extensionsUsed"] = sorted(used)
    text = json.dumps(document, separators=(",", ":")).encode()
    text += b" " * ((-len(text)) % 4)
    total = 12 + 8 + len(text) + 8 + buffer.size
    head = struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(text), b"JSON")
    return b"".join([head, text, struct.pack("<I4s", buffer.size, b"BIN\0"), *buffer.chunks])
