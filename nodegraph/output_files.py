"""Write a recipe's declared outputs into ``outputs/<recipe>/`` in the format each value type suits.

``write_output`` is a singledispatch registry like ``rerun_log.log_value``; every write is atomic.
"""

from __future__ import annotations

import io
from functools import singledispatch
from pathlib import Path
from typing import Any

import numpy as np

from . import codec
from .cache import atomic_write
from .values import Aggregate, ElementLibrary, FileSet, Image, Mesh


@singledispatch
def write_output(value: Any, directory: Path, stem: str) -> list[Path]:
    """Fallback: the value's .npz encoding (numpy.load reads it; ``__meta__.json`` holds the field tree)."""
    path = directory / f"{stem}.npz"
    atomic_write(path, codec.encode(value))
    return [path]


@write_output.register
def _(value: Mesh, directory: Path, stem: str) -> list[Path]:
    import trimesh

    mesh = trimesh.Trimesh(value.vertices, value.faces, vertex_colors=value.colors, process=False)
    path = directory / f"{stem}.ply"
    atomic_write(path, trimesh.exchange.ply.export_ply(mesh, encoding="binary"))
    return [path]


@write_output.register
def _(value: Image, directory: Path, stem: str) -> list[Path]:
    import imageio.v3 as iio

    buffer = io.BytesIO()
    iio.imwrite(buffer, np.asarray(value.pixels), extension=".png")
    path = directory / f"{stem}.png"
    atomic_write(path, buffer.getvalue())
    return [path]


@write_output.register
def _(value: FileSet, directory: Path, stem: str) -> list[Path]:
    paths = []
    for name, data in sorted(value.files.items()):
        if Path(name).name != name or name.startswith("."):
            raise ValueError(f"output file name '{name}' must be a plain file name")
        path = directory / name
        atomic_write(path, data)
        paths.append(path)
    return paths


def _glb(meshes: list[Mesh], names: list[str]) -> bytes:
    import trimesh

    scene = trimesh.Scene()
    for mesh, name in zip(meshes, names):
        colors = None if mesh.colors is None else np.asarray(mesh.colors)
        scene.add_geometry(trimesh.Trimesh(mesh.vertices, mesh.faces, vertex_colors=colors, process=False),
                           node_name=name, geom_name=name)
    return trimesh.exchange.gltf.export_glb(scene)


@write_output.register
def _(value: ElementLibrary, directory: Path, stem: str) -> list[Path]:
    """All elements of the library in one .glb, laid out as they are (each centred at the origin)."""
    path = directory / f"{stem}.glb"
    atomic_write(path, _glb(list(value.meshes), [f"{value.kind}_{i:03d}" for i in range(len(value))]))
    return [path]


@write_output.register
def _(value: Aggregate, directory: Path, stem: str) -> list[Path]:
    """The placed elements in world space, one glTF node each."""
    path = directory / f"{stem}.glb"
    meshes = [value.element_mesh(i) for i in range(len(value.placement))]
    atomic_write(path, _glb(meshes, [f"element_{i:05d}" for i in range(len(meshes))]))
    return [path]
