"""Log node outputs to Rerun with the archetype that fits each value type, one recording per run.

``log_value`` is a ``functools.singledispatch`` registry: the engine registers its generic values
(Mesh, Image, FileSet, Table); a node package that defines a new value type registers its own logger
with ``@log_value.register`` (the built-in ones: ``nodes.rerun_loggers``).
"""

from __future__ import annotations

import dataclasses
import os
import sys
import uuid
from functools import singledispatch
from pathlib import Path
from typing import Any

import numpy as np

from .context import EntityLogger, LogIndex
from .values import FileSet, Image, Mesh, Table


def rerun_module():
    import rerun as rr

    return rr


def partial_path(path: Path) -> Path:
    """Where a run's recording is written until the run completes: ``name.partial.rrd`` beside it."""
    return path.with_name(f"{path.stem}.partial{path.suffix}")


def has_display() -> bool:
    """True when a viewer window can open here (an X or Wayland display, or not Linux)."""
    return not sys.platform.startswith("linux") or bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class RunRecording:
    """One ``rr.RecordingStream`` per run, written to ``name.partial.rrd`` and renamed over ``name.rrd``
    only when the run completes, so an interrupted or failed run never replaces a complete recording
    (its partial file stays beside it, named as partial; the next complete run removes it).

    ``recording_id`` names the run (e.g. a digest of recipe and overrides), so runs of two settings
    are two recordings that a viewer shows side by side. ``spawn`` also streams to a viewer; a viewer
    that cannot start is reported through ``warn`` and the file is still written."""

    def __init__(
        self, path: str | Path, recipe_name: str, spawn: bool = False, recording_id: str | None = None, warn=None
    ):
        rr = rerun_module()
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.partial = partial_path(self.path)
        self.index = LogIndex()
        self.stream = rr.RecordingStream("nodegraph", recording_id=recording_id or str(uuid.uuid4()))
        self.stream.send_recording_name(recipe_name)
        sinks = [rr.FileSink(str(self.partial))]
        if spawn:
            try:
                self.stream.spawn(connect=False)
                sinks.append(rr.GrpcSink())
            except Exception as exc:  # no viewer binary, no port: the file is what matters
                if warn is not None:
                    warn(f"--spawn: the Rerun viewer did not start ({exc}); recording to {self.path} only")
        self.stream.set_sinks(*sinks)

    def logger(self, prefix: str) -> EntityLogger:
        return EntityLogger(self.stream, prefix, self.index)

    def close(self, complete: bool = True, blueprint=None) -> Path:
        """Send the blueprint, flush, write the footer (by disconnecting the sinks); a complete run's
        file replaces ``path``, an incomplete one stays at ``partial``. Returns where the file is."""
        if blueprint is not None:
            self.stream.send_blueprint(blueprint)
        self.stream.flush()
        self.stream.disconnect()
        if not complete:
            return self.partial
        os.replace(self.partial, self.path)
        return self.path


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
    log.log(
        "",
        rr.Mesh3D(
            vertex_positions=value.vertices.astype(np.float32),
            triangle_indices=value.faces.astype(np.uint32),
            vertex_normals=None if value.normals is None else value.normals.astype(np.float32),
            vertex_colors=mesh_colors(value),
        ),
        static=True,
    )


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
            log.send_columns(
                name,
                indexes=[rr.TimeColumn(value.index or "row", sequence=np.arange(len(column)))],
                columns=rr.Scalars.columns(scalars=column.astype(np.float64)),
            )
