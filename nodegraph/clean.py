"""What ``nodegraph clean`` prunes: the outputs of a recipe's earlier runs that no folder's last run wrote, the
``--set`` folders of earlier runs, and the partial recordings that stopped or failed runs left.

A recipe's runs write into its folders (``output_folder``: ``outputs/<recipe>/``, ``outputs/<recipe>_draft/`` and
the ``set_*`` folder of each ``--set``), each with the ``manifest.json`` of the run that wrote it last. The latest
run is the newest manifest among the folders whose manifest names the recipe file. Prunable: in every folder, the
files its manifest keeps from an earlier run (``earlier``); in every ``set_*`` folder but the latest run's, every
file its manifest lists (``files``, ``earlier``, its recording) and then the manifest; anywhere, a
``*.<pid>.partial.rrd`` whose process has ended. The recipe's own folder and its draft's keep their last run's
files: a draft or a ``--set`` run after the final render must not make the render prunable (a new user's first
``clean`` removed the main job's picture after a draft run). Only a file whose size and modification time are
still what its manifest recorded is removed: a file a user made or changed is never touched, nor is one no manifest
lists.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from .output_files import MANIFEST
from .output_folder import SETTINGS_PREFIX, folder_owner, outputs_root, recipe_folder
from .rerun_log import alive

PARTIAL = re.compile(r"^.+\.(\d+)\.partial\.rrd$")  # rerun_log.RunRecording's partial name: NAME.<pid>.partial.rrd


@dataclass
class Prunable:
    """What ``clean`` would remove: ``files`` (each with its size in bytes), and the manifests of the folders whose
    run is no longer the latest (``manifests``), removed once their files are."""

    files: dict[Path, int] = field(default_factory=dict)
    manifests: list[Path] = field(default_factory=list)

    @property
    def bytes(self) -> int:
        return sum(self.files.values())

    def folders(self) -> set[Path]:
        return {p.parent for p in self.files}


def _manifest(folder: Path) -> dict | None:
    try:
        manifest = json.loads((folder / MANIFEST).read_bytes())
    except (OSError, ValueError):
        return None
    return manifest if isinstance(manifest, dict) else None


def _folders(recipe: Path, name: str) -> list[Path]:
    """The recipe's folders (its own, its draft's) and the ``set_*`` folders inside them that exist."""
    found = []
    for draft in (False, True):
        base = recipe_folder(recipe, name, draft)
        if base.is_dir():
            found.append(base)
            found += sorted(p for p in base.iterdir() if p.is_dir() and p.name.startswith(SETTINGS_PREFIX))
    return found


def _unchanged(path: Path, record: dict) -> int | None:
    """``path``'s size when its size and modification time are what ``record`` says (as written); else None."""
    try:
        stat = path.stat()
    except OSError:
        return None
    if stat.st_size != record.get("bytes") or stat.st_mtime_ns != record.get("mtime_ns"):
        return None
    return stat.st_size


def _listed(folder: Path, records: dict) -> dict[Path, int]:
    """The files of ``records`` (a manifest's ``files`` or ``earlier``) in ``folder`` still as they were written."""
    kept = {}
    for name, record in records.items():
        if not isinstance(record, dict) or Path(name).is_absolute() or ".." in Path(name).parts:
            continue
        size = _unchanged(folder / name, record)
        if size is not None:
            kept[folder / name] = size
    return kept


def prunable(recipe: Path, name: str) -> Prunable:
    """What ``clean`` removes for the recipe file ``recipe`` (``name``: its ``name:``), nothing removed yet."""
    mine = Path(recipe).resolve()
    project = outputs_root(recipe).resolve().parent
    folders = _folders(recipe, name)
    manifests = {f: m for f in folders if (m := _manifest(f)) is not None and folder_owner(f, project) == mine}
    latest = max(manifests, key=lambda f: (f / MANIFEST).stat().st_mtime_ns, default=None)
    out = Prunable()
    for folder in folders:
        for partial in folder.glob("*.partial.rrd"):
            match = PARTIAL.match(partial.name)
            if match and not alive(int(match.group(1))):
                out.files[partial] = partial.stat().st_size
    for folder, manifest in manifests.items():
        out.files.update(_listed(folder, manifest.get("earlier") or {}))
        if folder == latest or not folder.name.startswith(SETTINGS_PREFIX):
            continue
        out.files.update(_listed(folder, manifest.get("files") or {}))
        recording = manifest.get("recording") or {}
        given = Path(recording.get("path", ""))
        path = folder / given.name  # named as the folder is (the manifest keeps it absolute)
        if given.parent.resolve() == folder.resolve() and (size := _unchanged(path, recording)) is not None:
            out.files[path] = size
        out.manifests.append(folder / MANIFEST)
    return out


def remove(found: Prunable) -> None:
    """Remove what ``prunable`` found, then each folder it leaves empty (a ``set_*`` folder of an earlier run)."""
    for path in [*found.files, *found.manifests]:
        path.unlink(missing_ok=True)
    for folder in sorted({p.parent for p in [*found.files, *found.manifests]}, key=lambda f: -len(f.parts)):
        try:
            folder.rmdir()
        except OSError:  # not empty: the latest run's files, or a user's own
            pass
