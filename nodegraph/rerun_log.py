"""Log node outputs to Rerun with the archetype that fits each value type, one recording per run.

``log_value`` is a ``functools.singledispatch`` registry: a plugin that defines a new value type
registers its own logger with ``@log_value.register``.
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
from .values import (Aggregate, DistanceField, ElementLibrary, FileSet, Image, Mesh, ParticleState, Placement,
                     ShadedScene, SphereSet, Table, Volume)

MAX_VOLUME_POINTS = 200_000


def _rr():
    import rerun as rr

    return rr


class RunRecording:
    """One ``rr.RecordingStream`` per run, saved to a temporary file and renamed when closed."""

    def __init__(self, path: str | Path, recipe_name: str, spawn: bool = False):
        rr = _rr()
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
    rr = _rr()
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


def _colors(mesh: Mesh):
    if mesh.colors is None:
        return None
    colors = np.asarray(mesh.colors)
    if colors.dtype != np.uint8:
        colors = (np.clip(colors, 0.0, 1.0) * 255).astype(np.uint8)
    return colors


@log_value.register
def _(value: Mesh, log: EntityLogger) -> None:
    rr = _rr()
    log.log("", rr.Mesh3D(vertex_positions=value.vertices.astype(np.float32), triangle_indices=value.faces.astype(np.uint32),
                          vertex_normals=None if value.normals is None else value.normals.astype(np.float32),
                          vertex_colors=_colors(value)), static=True)


@log_value.register
def _(value: ElementLibrary, log: EntityLogger) -> None:
    # Lay the elements out on a row so the whole library can be seen at once.
    offset = 0.0
    for i, mesh in enumerate(value.meshes):
        lo, hi = mesh.bounds
        shift = np.array([offset - lo[0], 0.0, 0.0])
        log_value(dataclasses.replace(mesh, vertices=mesh.vertices + shift), EntityLogger(log.recording, log.path(f"{i}")))
        offset += (hi[0] - lo[0]) * 1.2


@log_value.register
def _(value: SphereSet, log: EntityLogger) -> None:
    rr = _rr()
    log.log("", rr.Points3D(value.centers.astype(np.float32), radii=value.radii.astype(np.float32)), static=True)


@log_value.register
def _(value: Volume, log: EntityLogger) -> None:
    """Inside cells as points (subsampled; a distance field coloured by depth) and the middle z-slice."""
    rr = _rr()
    data = np.asarray(value.data)
    inside = data > 0
    step = max(1, int(np.ceil(np.count_nonzero(inside) / MAX_VOLUME_POINTS)))
    centers = value.cell_centers(inside)[::step].astype(np.float32)
    colors = None
    if isinstance(value, DistanceField) and len(centers):
        depth = data[inside][::step]
        shade = (255 * depth / depth.max()).astype(np.uint8)
        colors = np.stack([shade, 64 + shade // 2, 255 - shade], axis=1).astype(np.uint8)
    log.log("cells", rr.Points3D(centers, colors=colors, radii=np.float32(value.voxel_size * 0.5)), static=True)
    middle = data[:, :, data.shape[2] // 2].astype(np.float32)
    span = float(np.abs(middle).max()) or 1.0
    log.log("slice", rr.Tensor(middle / span), static=True)


@log_value.register
def _(value: Placement, log: EntityLogger) -> None:
    rr = _rr()
    log.log("positions", rr.Points3D(value.positions.astype(np.float32), class_ids=value.kinds.astype(np.uint16)),
            static=True)
    if len(value):
        log.log("normals", rr.Arrows3D(origins=value.positions.astype(np.float32),
                                       vectors=value.normals.astype(np.float32) * 0.5), static=True)


def elements_mesh3d(value: Aggregate):
    """Every element of the aggregate in world space as one ``Mesh3D`` (None when empty)."""
    mesh = value.combined_mesh()
    if mesh is None:
        return None
    return _rr().Mesh3D(vertex_positions=mesh.vertices.astype(np.float32), triangle_indices=mesh.faces.astype(np.uint32))


@log_value.register
def _(value: Aggregate, log: EntityLogger) -> None:
    archetype = elements_mesh3d(value)
    if archetype is not None:
        log.log("elements", archetype, static=True)


@log_value.register
def _(value: ParticleState, log: EntityLogger) -> None:
    rr = _rr()
    log.log("", rr.Points3D(value.positions.astype(np.float32), radii=value.radii.astype(np.float32),
                            class_ids=(value.element % 65535).astype(np.uint16)), static=True)


@log_value.register
def _(value: ShadedScene, log: EntityLogger) -> None:
    for i, mesh in enumerate(value.meshes):
        log_value(mesh, EntityLogger(log.recording, log.path(f"{i}")))


@log_value.register
def _(value: Image, log: EntityLogger) -> None:
    log.log("", _rr().Image(value.pixels), static=True)


@log_value.register
def _(value: FileSet, log: EntityLogger) -> None:
    rr = _rr()
    listing = "\n".join(f"{name}: {len(data)} bytes" for name, data in sorted(value.files.items()))
    log.log("", rr.TextDocument(listing), static=True)


@log_value.register
def _(value: Table, log: EntityLogger) -> None:
    rr = _rr()
    for name, column in value.columns.items():
        column = np.asarray(column)
        if column.dtype.kind in "fiu" and column.ndim == 1 and len(column):
            log.send_columns(name, indexes=[rr.TimeColumn(value.index or "row", sequence=np.arange(len(column)))],
                             columns=rr.Scalars.columns(scalars=column.astype(np.float64)))
