"""Log node outputs to Rerun with the archetype that fits each value type, one recording per run.

``log_value`` is a ``functools.singledispatch`` registry: the engine registers its generic values
(Mesh, Image, FileSet, Table); a node package that defines a new value type registers its own logger
with ``@log_value.register`` (the built-in ones: ``nodes.rerun_loggers``).
"""

from __future__ import annotations

import dataclasses
import os
import uuid
from functools import singledispatch
from pathlib import Path
from typing import Any

import numpy as np

from .context import EntityLogger
from .values import FileSet, Image, Mesh, Table


def rerun_module():
    import rerun as rr

    return rr


class RunRecording:
    """One ``rr.RecordingStream`` per run, saved to a temporary file and renamed when closed."""

    def __init__(self, path: str | Path, recipe_name: str, spawn: bool = False):
        rr = rerun_module()
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._tmp = self.path.with_name(f".{self.path.name}.{uuid.uuid4().hex[:8]}.tmp")
        self.stream = rr.RecordingStream("nodegraph", recording_id=str(uuid.uuid4()))
        self.stream.send_recording_name(recipe_name)
        if spawn:
            self.stream.spawn(connect=False)
            self.stream.set_sinks(rr.FileSink(str(self._tmp)), rr.GrpcSink())
        else:
            self.stream.save(str(self._tmp))

    def logger(self, prefix: str) -> EntityLogger:
        return EntityLogger(self.stream, prefix)

    def close(self, keep: bool = True) -> None:
        """Flush, write the footer (by disconnecting the sink) and move the file into place."""
        self.stream.flush()
        self.stream.disconnect()
        if keep:
            os.replace(self._tmp, self.path)
        else:
            self._tmp.unlink(missing_ok=True)


@singledispatch
def log_value(value: Any, log: EntityLogger) -> None:
    """Fallback: log the scalar fields of a dataclass as text, so every output leaves a trace."""
    rr = rerun_module()
    if dataclasses.is_dataclass(value):
        summary = {f.name: _describe(getattr(value, f.name)) for f in dataclasses.fields(value)}
        log.log("", rr.TextDocument("\n".join(f"{k}: {v}" for k, v in summary.items())), static=True)
    else:
        log.log("", rr.TextDocument(repr(value)[:2000]), static=True)


def _describe(obj: Any) -> str:
    if isinstance(obj, np.ndarray):
        return f"array{obj.shape} {obj.dtype}"
    if isinstance(obj, (list, tuple)):
        return f"{type(obj).__name__} of {len(obj)}"
    return repr(obj)[:200]


def mesh_colors(mesh: Mesh):
    if mesh.colors is None:
        return None
    colors = np.asarray(mesh.colors)
    if colors.dtype != np.uint8:
        colors = (np.clip(colors, 0.0, 1.0) * 255).astype(np.uint8)
    return colors


@log_value.register
def _(value: Mesh, log: EntityLogger) -> None:
    rr = rerun_module()
    log.log("", rr.Mesh3D(vertex_positions=value.vertices.astype(np.float32), triangle_indices=value.faces.astype(np.uint32),
                          vertex_normals=None if value.normals is None else value.normals.astype(np.float32),
                          vertex_colors=mesh_colors(value)), static=True)


@log_value.register
def _(value: Image, log: EntityLogger) -> None:
    log.log("", rerun_module().Image(value.pixels), static=True)


@log_value.register
def _(value: FileSet, log: EntityLogger) -> None:
    rr = rerun_module()
    listing = "\n".join(f"{name}: {len(data)} bytes" for name, data in sorted(value.files.items()))
    log.log("", rr.TextDocument(listing), static=True)


@log_value.register
def _(value: Table, log: EntityLogger) -> None:
    rr = rerun_module()
    for name, column in value.columns.items():
        column = np.asarray(column)
        if column.dtype.kind in "fiu" and column.ndim == 1 and len(column):
            log.send_columns(name, indexes=[rr.TimeColumn(value.index or "row", sequence=np.arange(len(column)))],
                             columns=rr.Scalars.columns(scalars=column.astype(np.float64)))
