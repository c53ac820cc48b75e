"""Write a recipe's declared outputs into ``outputs/<recipe>/`` in the format each value type suits.

``write_output`` is a singledispatch registry like ``rerun_log.log_value``: the engine registers its
generic values (Mesh → .ply, Image → .png, FileSet → its files, Table → .csv, anything else → a .npz
with members named by field path); a node package
registers its own types (the built-in ones: ``nodes.output_writers``). Every write is atomic.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import io
import json
import zipfile
from collections.abc import Callable
from functools import singledispatch
from pathlib import Path
from typing import Any

import numpy as np

from .cache import atomic_write
from .values import FileSet, Image, Mesh, Table

PNG_LEVEL = 1  # zlib level of written PNGs (Image outputs)


def flat_arrays(value: Any, prefix: str = "") -> dict[str, np.ndarray]:
    """The arrays of a value by field path (``positions``, ``libraries.0.kind``): what ``numpy.load``
    shows of it. Plain fields become 0-d arrays, strings unicode arrays (no pickle)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        items = [(f.name, getattr(value, f.name)) for f in dataclasses.fields(value)]
    elif isinstance(value, dict):
        items = sorted((str(k), v) for k, v in value.items())
    elif isinstance(value, (list, tuple)):
        items = [(str(i), v) for i, v in enumerate(value)]
    else:
        if value is None:
            return {}
        if isinstance(value, bytes):
            value = np.frombuffer(value, np.uint8)
        array = np.asarray(value)
        return {} if array.dtype == object else {prefix or "value": array}
    out: dict[str, np.ndarray] = {}
    for name, item in items:
        out.update(flat_arrays(item, f"{prefix}.{name}" if prefix else name))
    return out


def named_npz(arrays: dict[str, np.ndarray]) -> bytes:
    """A deterministic .npz (fixed member times, no pickle) with one member per named array."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_STORED) as archive:
        for name, array in arrays.items():
            member = io.BytesIO()
            np.lib.format.write_array(member, np.ascontiguousarray(array), allow_pickle=False)
            archive.writestr(zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0)), member.getvalue())
    return buffer.getvalue()


@singledispatch
def write_output(value: Any, directory: Path, stem: str) -> list[Path]:
    """Fallback: a .npz whose members are named by field path (``numpy.load(f).files`` lists them)."""
    path = directory / f"{stem}.npz"
    atomic_write(path, named_npz(flat_arrays(value)))
    return [path]


@write_output.register
def _(value: Table, directory: Path, stem: str) -> list[Path]:
    """A table of 1-D columns as CSV (a header row of column names); other tables as a named .npz. Columns in name
    order, the table's index first: a dict's order is not part of a value (``codec`` stores it sorted), so a table
    read back from the cache would otherwise write its columns in another order than the run that computed it."""
    names = sorted(value.columns, key=lambda name: (name != value.index, name))
    columns = {name: np.asarray(value.columns[name]) for name in names}
    if not all(c.ndim == 1 for c in columns.values()):
        return write_output.dispatch(object)(value, directory, stem)
    path = directory / f"{stem}.csv"
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows(zip(*(_csv_cells(c) for c in columns.values())))
    atomic_write(path, buffer.getvalue().encode())
    return [path]


def _csv_cells(column: np.ndarray) -> list:
    """Cells of a column: floats written exactly (repr round-trips), the rest as they print."""
    if column.dtype.kind == "f":
        return [repr(float(x)) for x in column]
    return [x.item() if hasattr(x, "item") else x for x in column]


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
    # zlib's fastest level: the main job's 1280 × 720 preview in 0.06 CPU s, not 0.25 at the default (6), the
    # file 22 % larger (1.04 MB, not 0.85); the same pixels (the run writes it after the preview: its critical path)
    iio.imwrite(buffer, np.asarray(value.pixels), extension=".png", compress_level=PNG_LEVEL)
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


MANIFEST = "manifest.json"


def settle_earlier(
    directory: Path,
    files: list[Path],
    digest: str,
    current: Callable[[str], str | None] | None = None,
    writers: str | None = None,
) -> tuple[dict[str, Any], dict[Path, str | None]]:
    """What the folder's last manifest lists that this run (recipe ``digest``, writing ``files``) did not write
    again, settled by what each file was written from: a file whose step (``from``: a node instance) has the same
    cache key now (``current(label)``, None: no such step) and was written by the same ``writers`` is still this
    recipe's: kept, returned to be listed as ``earlier`` in this run's manifest; one whose step's key changed is
    stale: removed, so no output of other settings sits beside this run's (its value stays in the cache: running
    those settings again writes it in seconds). A file listed without its step (a manifest from before this rule) is
    kept when the whole recipe's ``digest`` is the same. Returns (kept records by name, each removed path with the
    step it was written from, None where not recorded). A file this run wrote is never removed; a file changed since
    it was written is someone's own: left, and said as not from this run (``executor``); a file no manifest lists is
    never touched."""
    try:
        manifest = json.loads((directory / MANIFEST).read_bytes())
        records = {**manifest.get("earlier", {}), **manifest["files"]}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return {}, {}
    written = {str(path.relative_to(directory)) for path in files}
    kept: dict[str, Any] = {}
    removed: dict[Path, str | None] = {}
    for name, record in records.items():
        path = directory / name
        if name in written or Path(name).is_absolute() or ".." in Path(name).parts:
            continue
        try:
            if _stamp(path) != {"bytes": record["bytes"], "mtime_ns": record.get("mtime_ns")}:
                continue
        except (OSError, KeyError, TypeError):
            continue
        if current is not None and record.get("from") and manifest.get("writers"):
            valid = current(record["from"]) == record.get("key") and manifest["writers"] == writers
        else:
            valid = manifest.get("digest") == digest
        if valid:
            kept[name] = {"written": manifest.get("written"), **record}
        else:
            path.unlink(missing_ok=True)  # a run of the same settings at once may have settled it first
            removed[path] = record.get("from")
            if path.parent != directory and not any(path.parent.iterdir()):
                path.parent.rmdir()  # a variant family's folder, emptied
    return kept, removed


def earlier_outputs(directory: Path) -> list[str]:
    """The files the folder's manifest lists as ``earlier``: of the same settings, kept from an earlier run."""
    try:
        return list(json.loads((directory / MANIFEST).read_bytes()).get("earlier", {}))
    except (OSError, ValueError, AttributeError):
        return []


def write_manifest(
    directory: Path,
    files: list[Path],
    run: dict[str, Any],
    recording: Path | None = None,
    earlier: dict[str, Any] | None = None,
    sources: dict[Path, tuple[str, str]] | None = None,
) -> Path:
    """``manifest.json`` beside the outputs: which run wrote them (``run``: recipe, digest, seed, overrides,
    time, the run's ``output_key``, ...) and the sha256, size and modification time of each file it wrote
    (and of its ``recording``); ``earlier``: files an earlier run of the same settings wrote that this one kept
    (``settle_earlier``); files in the folder it lists in neither are not from this run's settings. ``sources``:
    the step each file was written from and that step's cache key (``from``, ``key``: what ``settle_earlier``
    judges a file by)."""
    listing = {}
    for path in files:
        data = path.read_bytes()
        listing[str(path.relative_to(directory))] = {
            "sha256": hashlib.sha256(data).hexdigest(),
            "bytes": len(data),
            "mtime_ns": path.stat().st_mtime_ns,
        }
        if sources and path in sources:
            listing[str(path.relative_to(directory))].update(zip(("from", "key"), sources[path]))
    run = dict(run, files=listing)
    if earlier:
        run["earlier"] = earlier
    if recording is not None:
        run["recording"] = {"path": str(recording.resolve()), **_stamp(recording)}
    path = directory / MANIFEST
    atomic_write(path, json.dumps(run, indent=1, sort_keys=True).encode())
    return path


def current_outputs(directory: Path, output_key: str, recording: Path | None) -> list[Path] | None:
    """The files a run with ``output_key`` wrote into ``directory`` when they are all still there as it left
    them (size and modification time, as ``make`` judges a file), and its ``recording`` too; else None.
    A run whose outputs are current writes nothing: the same key means the same bytes."""
    try:
        manifest = json.loads((directory / MANIFEST).read_bytes())
        if manifest.get("output_key") != output_key:
            return None
        files = []
        for name, record in manifest["files"].items():
            path = directory / name
            if _stamp(path) != {"bytes": record["bytes"], "mtime_ns": record.get("mtime_ns")}:
                return None
            files.append(path)
        if recording is not None:
            kept = manifest.get("recording") or {}
            if kept.get("path") != str(recording.resolve()) or _stamp(recording) != {
                "bytes": kept.get("bytes"),
                "mtime_ns": kept.get("mtime_ns"),
            }:
                return None
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None
    return files


def _stamp(path: Path) -> dict[str, int]:
    stat = path.stat()
    return {"bytes": stat.st_size, "mtime_ns": stat.st_mtime_ns}
