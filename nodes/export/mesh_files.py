"""A shaded scene as one PLY or OBJ mesh with sRGB vertex colours.

OBJ goes through trimesh's exporter; PLY is written with numpy record arrays because trimesh's
exporter took ~10× longer on a 100k-vertex scene (it re-validates the mesh), which the ≤ 5 s
re-run target of a shade change cannot afford.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..values import ShadedScene


def linear_to_srgb8(colors: np.ndarray) -> np.ndarray:
    """Linear RGB (clipped to [0, 1]) → 8-bit sRGB: PLY/OBJ vertex colours and preview pixels, shape (..., 3)."""
    c = np.clip(np.asarray(colors, np.float64)[..., :3], 0.0, 1.0)
    srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


def rowwise(blocks: list[np.ndarray], convert) -> list[np.ndarray]:
    """``convert`` (a row-by-row map: a dtype cast, ``linear_to_srgb8``, unit normals) of each block, applied once
    to their concatenation and split back: the same rows as a call per block, without a few numpy calls per mesh."""
    if not blocks:
        return []
    return np.split(convert(np.concatenate(blocks)), np.cumsum([len(b) for b in blocks])[:-1])


def stacked(meshes) -> tuple[np.ndarray, np.ndarray]:
    """Meshes as one (vertices, faces) array pair, each mesh's face indices shifted past the previous ones."""
    starts = np.cumsum([0] + [len(m.vertices) for m in meshes])
    return (np.concatenate([m.vertices for m in meshes]), np.concatenate([m.faces + s for m, s in zip(meshes, starts)]))


def combined_arrays(scene: ShadedScene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All meshes as one (vertices, faces, sRGB colours), vertices kept apart per element."""
    meshes = [m for m in scene.meshes if len(m.faces)]
    if not meshes:
        raise ValueError("scene: no mesh with faces to export")
    vertices, faces = stacked(meshes)
    srgb = iter(rowwise([m.colors[:, :3] for m in meshes if m.colors is not None], linear_to_srgb8))
    colors = np.concatenate(
        [next(srgb) if m.colors is not None else np.full((len(m.vertices), 3), 204, np.uint8) for m in meshes]
    )
    return vertices, faces, colors


PLY_TYPES = {"<f4": "float", "|u1": "uchar"}


def binary_ply(blocks: list[tuple[tuple[str, ...], np.ndarray]], faces: np.ndarray, comment: str = "") -> bytes:
    """Binary little-endian PLY: vertex properties from (names, (n, len(names)) float32|uint8 block) pairs,
    then triangle lists. Written with numpy records (see the module note on trimesh's exporter)."""
    fields = [(name, block.dtype.str) for names, block in blocks for name in names]
    vertices = np.zeros(len(blocks[0][1]), dtype=fields)
    for names, block in blocks:
        for k, name in enumerate(names):
            vertices[name] = block[:, k]
    triangles = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    triangles["n"] = 3
    triangles["i"] = faces
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        + (f"comment {comment}\n" if comment else "")
        + f"element vertex {len(vertices)}\n"
        + "".join(f"property {PLY_TYPES[dtype]} {name}\n" for name, dtype in fields)
        + f"element face {len(triangles)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    return header.encode() + vertices.tobytes() + triangles.tobytes()


def write_ply(path: Path, vertices, faces, normals, colors, translucency=None) -> None:
    """A Mitsuba PLY shape at ``path``: binary little-endian PLY with float normals, float linear colours
    (Mitsuba: ``vertex_color``) and optionally a per-vertex diffuse transmission (``trans_x``: Mitsuba's
    ``vertex_trans``)."""
    names = ("x", "y", "z", "nx", "ny", "nz", "r", "g", "b")
    columns = [vertices, normals, colors[:, :3]]
    if translucency is not None:
        names += ("trans_x",)
        columns.append(np.asarray(translucency).reshape(-1, 1))
    rows = np.hstack(columns).astype("<f4")
    path.write_bytes(binary_ply([(names, rows)], faces))


def ply_bytes(scene: ShadedScene) -> bytes:
    """Binary little-endian PLY: float xyz, uchar sRGB colours, triangle lists."""
    points, triangles, colors = combined_arrays(scene)
    return binary_ply(
        [(("x", "y", "z"), points.astype("<f4")), (("red", "green", "blue"), colors)],
        triangles,
        comment="nodegraph export: sRGB vertex colours",
    )


def obj_bytes(scene: ShadedScene) -> bytes:
    import trimesh

    vertices, faces, colors = combined_arrays(scene)
    mesh = trimesh.Trimesh(vertices, faces, vertex_colors=colors, process=False)
    text = trimesh.exchange.obj.export_obj(mesh, include_normals=False, include_color=True, include_texture=False)
    return text.encode()
