"""Log node outputs to Rerun with the archetype that fits each value type, one recording per run.

``log_value`` is a ``functools.singledispatch`` registry: the engine registers its generic values
(Mesh, Image, FileSet, Table); a node package that defines a new value type registers its own logger
with ``@log_value.register`` (the built-in ones: ``nodes.rerun_loggers``).
"""

from __future__ import annotations

import dataclasses
import glob
import os
import sys
import uuid
from functools import singledispatch
from pathlib import Path
from typing import Any

import numpy as np

from . import interrupt
from .cache import Fragment
from .context import EntityLogger, LogIndex
from .errors import NodegraphError
from .values import FileSet, Image, Mesh, Table


def rerun_module():
    import rerun as rr

    return rr


def partial_path(path: Path, pid: int | None = None) -> Path:
    """Where process ``pid`` (this one by default) writes a recording until its run completes:
    ``name.<pid>.partial.rrd`` beside it, so two runs of the same recipe and settings at once never write or
    move each other's partial file."""
    return path.with_name(f"{path.stem}.{os.getpid() if pid is None else pid}.partial{path.suffix}")


def remove_stale_partials(path: Path) -> list[Path]:
    """Remove the partial recordings beside ``path`` that no running process writes: what failed or killed
    runs left (a complete run ends them), never the one a run still in progress writes. Returns them."""
    removed = []
    for partial in path.parent.glob(f"{glob.escape(path.stem)}.*.partial{path.suffix}"):
        pid = partial.name[len(path.stem) + 1 : -len(f".partial{path.suffix}")]
        if pid.isdigit() and not alive(int(pid)):
            partial.unlink(missing_ok=True)
            removed.append(partial)
    return removed


def alive(pid: int) -> bool:
    """True while process ``pid`` runs (one of another user's counts); a zombie does not: a run killed with its
    supervising parent waits as one until something reaps it, which in a container may be never."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    try:  # Linux: the state after the command's closing parenthesis
        return Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0] != "Z"
    except (OSError, IndexError):
        return True


def has_display() -> bool:
    """True when a viewer window can open here (an X or Wayland display, or not Linux)."""
    return not sys.platform.startswith("linux") or bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def new_stream(recording_id: str):
    """A stream of recording ``recording_id`` that stamps no wall-clock ``log_time``: what a run logs
    depends only on the recipe, so a cached re-run's recording equals a cold run's in content."""
    rr = rerun_module()
    stream = rr.RecordingStream("nodegraph", recording_id=recording_id)
    stream.set_log_time_enabled(False)
    return stream


class NodeCapture:
    """What one node instance logs (as it runs, then its outputs) captured as an .rrd fragment at ``path``.

    The fragment is replayed into the run's recording (``RunRecording.append``) and kept with the
    node's cache entry, so a cached re-run appends these chunks instead of logging the values again.
    ``live`` also streams them to the run's viewer as they are logged."""

    def __init__(self, path: Path, recording_id: str, live: bool = False):
        rr = rerun_module()
        self.path = Path(path)
        self.index = LogIndex()
        self.live = live
        self.stream = new_stream(recording_id)
        self.stream.set_sinks(rr.FileSink(str(self.path)), *([rr.GrpcSink()] if live else []))

    def logger(self, prefix: str) -> EntityLogger:
        return EntityLogger(self.stream, prefix, self.index)

    def close(self, entity: str, loggers: str) -> Fragment:
        """Flush and write the fragment's footer: what was logged under ``entity``, by ``loggers``."""
        self.stream.flush()
        self.stream.disconnect()
        return Fragment(self.path, entity, self.index.relative(entity), loggers)


class RunRecording:
    """One recording per run, written to ``name.<pid>.partial.rrd`` and renamed over ``name.rrd``
    only when the run completes, so an interrupted or failed run never replaces a complete recording
    (its partial file stays beside it, named as partial, until the next complete run; a run stopped by
    Ctrl-C or SIGTERM removes it: ``executor.run_recipe``, ``interrupt``), and two runs at once each write
    their own.

    ``recording_id`` names the run (e.g. a digest of recipe and overrides), so runs of two settings
    are two recordings that a viewer shows side by side. ``spawn`` also streams to a viewer (a second
    stream of the same recording); a viewer that cannot start is reported through ``warn`` and the
    file is still written. Nodes log into a ``NodeCapture`` whose fragment is then ``append``-ed."""

    def __init__(
        self, path: str | Path, recipe_name: str, spawn: bool = False, recording_id: str | None = None, warn=None
    ):
        rr = rerun_module()
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.partial = partial_path(self.path)
        interrupt.note(self.partial)
        self.index = LogIndex()
        self.loggers = logger_digest()
        self.recording_id = recording_id or str(uuid.uuid4())
        self.stream = new_stream(self.recording_id)
        self.stream.set_sinks(rr.FileSink(str(self.partial)))
        self.viewer = None
        if spawn:
            try:
                viewer = new_stream(self.recording_id)
                viewer.spawn(connect=False)
                viewer.set_sinks(rr.GrpcSink())
                self.viewer = viewer
            except Exception as exc:  # no viewer binary, no port: the file is what matters
                if warn is not None:
                    warn(f"--spawn: the Rerun viewer did not start ({exc}); recording to {self.path} only")
        for stream in self.streams:
            stream.send_recording_name(recipe_name)

    @property
    def streams(self) -> list:
        return [self.stream] + ([self.viewer] if self.viewer is not None else [])

    def logger(self, prefix: str) -> EntityLogger:
        """Log straight into the file (what a test or a tool without a cache does)."""
        return EntityLogger(self.stream, prefix, self.index)

    def capture(self, path: Path) -> NodeCapture:
        """A capture of one node instance's logging into the fragment ``path`` (live in the viewer)."""
        return NodeCapture(path, self.recording_id, live=self.viewer is not None)

    def append(self, fragment: Path, entity: str, logged: dict[str, list[str]], stored_as: str, live: bool) -> None:
        """Send the chunks of ``fragment`` (logged under ``stored_as``) into this recording under ``entity``;
        ``logged`` maps paths below the entity to their archetypes (for the blueprint). ``live``: the
        viewer saw them while they were logged."""
        from rerun.chunk import RrdReader

        chunks = RrdReader(str(fragment)).stream().filter(content=f"{stored_as}/**")
        if stored_as != entity:  # an identical node elsewhere in the recipe (same cache key) logged it
            cut = len(stored_as)
            chunks = chunks.map(lambda chunk: chunk.with_entity_path(entity + chunk.entity_path[cut:]))
        targets = [self.stream] if live or self.viewer is None else self.streams
        if len(targets) == 1:
            targets[0].send_chunks(chunks)
        else:
            loaded = chunks.to_chunks()
            for stream in targets:
                stream.send_chunks(loaded)
        self.index.add_relative(entity, logged)

    def close(self, complete: bool = True, blueprint=None) -> Path:
        """Send the blueprint, flush, write the footer (by disconnecting the sinks); a complete run's
        file replaces ``path``, an incomplete one stays at ``partial``. Returns where the file is."""
        for stream in self.streams:
            if blueprint is not None:
                stream.send_blueprint(blueprint)
            stream.flush()
            stream.disconnect()
        if not complete:
            return self.partial
        os.replace(self.partial, self.path)
        remove_stale_partials(self.path)
        return self.path


def logger_digest() -> str:
    """A digest of what an output's logged form depends on besides the value: the rerun-sdk version and the
    source of every registered ``log_value`` implementation (the engine's, the node packages', plugins') and of
    the functions their modules import from their own package (e.g. a shared drawing helper)."""
    from importlib.metadata import version

    return dispatch_digest(log_value, version("rerun-sdk"))  # the version without importing rerun (≈ 1 s)


def dispatch_digest(dispatcher, salt: str = "") -> str:
    """sha256 (16 hex digits) of ``salt`` and the source files of every implementation registered on the
    singledispatch ``dispatcher`` and of the functions their modules import from their own package."""
    import hashlib
    import inspect

    digest = hashlib.sha256(salt.encode())
    sources = {inspect.getsourcefile(fn) or "" for fn in dispatcher.registry.values()}
    for fn in list(dispatcher.registry.values()):  # and the helpers those modules import from their own package
        module = sys.modules.get(fn.__module__)
        package = fn.__module__.partition(".")[0]
        for helper in vars(module).values() if module is not None else ():
            if inspect.isfunction(helper) and helper.__module__.partition(".")[0] == package:
                sources.add(inspect.getsourcefile(helper) or "")
    for source in sorted(sources):
        digest.update(Path(source).read_bytes() if source else b"?")
    return digest.hexdigest()[:16]


def merge_recordings(parts: list[Path], path: Path) -> Path:
    """Write the recordings of ``parts`` into one .rrd at ``path`` (each stays its own recording, e.g. one
    per sweep point, for a viewer to show side by side), by Rerun's own ``rerun rrd merge``; written to
    this process's ``partial_path`` and renamed, so ``path`` is a complete file or the previous one."""
    import subprocess

    partial = partial_path(path)
    interrupt.note(partial)
    done = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "merge", "-o", str(partial), *map(str, parts)],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        partial.unlink(missing_ok=True)
        raise NodegraphError(f"cannot write {path}: rerun rrd merge failed: {done.stderr.strip()[-500:]}")
    os.replace(partial, path)
    return path


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
