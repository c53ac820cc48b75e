"""Write a recipe's declared outputs into ``outputs/<recipe>/`` in the format each value type suits.

``write_output`` is a singledispatch registry like ``rerun_log.log_value``: the engine registers its
generic values (Mesh → .ply, Image → .png, FileSet → its files, anything else → .npz); a node package
registers its own types (the built-in ones: ``nodes.output_writers``). Every write is atomic.
"""

from __future__ import annotations

import io
from functools import singledispatch
from pathlib import Path
from typing import Any

import numpy as np

from . import codec
from .cache import atomic_write
from .values import FileSet, Image, Mesh


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
