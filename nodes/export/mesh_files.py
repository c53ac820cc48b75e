"""A shaded scene as one PLY or OBJ mesh with sRGB vertex colours (trimesh's exporters)."""

from __future__ import annotations

import numpy as np

from nodegraph.values import ShadedScene


def linear_to_srgb8(colors: np.ndarray) -> np.ndarray:
    """Linear RGB in [0, 1] → 8-bit sRGB (the convention of PLY/OBJ vertex colours)."""
    c = np.clip(np.asarray(colors, np.float64)[:, :3], 0.0, 1.0)
    srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


def combined_trimesh(scene: ShadedScene):
    """All meshes in one trimesh (vertices kept apart per element), vertex colours in sRGB."""
    import trimesh

    meshes = [m for m in scene.meshes if len(m.faces)]
    if not meshes:
        raise ValueError("scene: no mesh with faces to export")
    starts = np.cumsum([0] + [len(m.vertices) for m in meshes])
    vertices = np.concatenate([m.vertices for m in meshes])
    faces = np.concatenate([m.faces + s for m, s in zip(meshes, starts)])
    colors = np.concatenate([linear_to_srgb8(m.colors) if m.colors is not None
                             else np.full((len(m.vertices), 3), 204, np.uint8) for m in meshes])
    return trimesh.Trimesh(vertices, faces, vertex_colors=colors, process=False)


def ply_bytes(scene: ShadedScene) -> bytes:
    import trimesh

    return trimesh.exchange.ply.export_ply(combined_trimesh(scene), encoding="binary")


def obj_bytes(scene: ShadedScene) -> bytes:
    import trimesh

    text = trimesh.exchange.obj.export_obj(combined_trimesh(scene), include_normals=False, include_color=True,
                                           include_texture=False)
    return text.encode()
