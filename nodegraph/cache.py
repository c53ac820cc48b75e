"""Content-addressed result cache: entries by cache key, output blobs by the sha256 of their bytes.

Layout under the cache directory::

    CACHEDIR.TAG            marks the directory as a nodegraph cache (https://bford.info/cachedir/)
    entries/ab/<key>.json   {"key", "node", "type", "outputs": {port: {"blob": sha, "size": n}}}
    blobs/cd/<sha>.npz      one encoded value (see ``codec``); identical outputs are stored once
    rerun/ab/<key>.rrd      what the node logged to Rerun (as it ran, then its outputs): replayed into
                            a cached re-run's recording instead of logging the values again
    checkpoints/<key>.npz   a long node's progress while it runs (``checkpoint``), removed when it completes

Every file is written to a temporary name in its final directory and renamed into place, blobs and
the Rerun fragment before the entry that names them, so a crash at any moment leaves either no entry or
a whole one (a fragment is checked against the sha256 its entry records before it is replayed). A blob
whose bytes no longer hash to its name is reported as corruption and recomputed. ``clear`` removes only
what a cache holds, and only from a directory carrying the marker.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import codec
from .errors import CacheCorruption, NodegraphError

DEFAULT_DIR = ".nodegraph/cache"
ENV_VAR = "NODEGRAPH_CACHE"


MARKER = "CACHEDIR.TAG"
MARKER_TEXT = (
    b"Signature: 8a477f597d28d172789f06886806bc55\n"
    b"# This directory is a nodegraph cache: `nodegraph cache clear` empties it.\n"
)
_UMASK = os.umask(0)
os.umask(_UMASK)


def default_cache_dir() -> Path:
    return Path(os.environ.get(ENV_VAR) or DEFAULT_DIR)


def check_writable(directory: Path, what: str, fix: str) -> None:
    """Fail before any compute when ``directory`` cannot be created or written (read-only disk, a file
    in the way), naming the path and ``fix``."""
    try:
        directory.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".nodegraph-probe.", dir=directory)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        reason = (
            "a file is in the way"
            if isinstance(exc, (FileExistsError, NotADirectoryError))
            else (exc.strerror or str(exc)).lower()
        )
        raise NodegraphError(f"cannot write the {what} at {directory}: {reason}; {fix}") from None


def atomic_write(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so that readers see the old file or the whole new one, never a part."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)  # as open() would make it (mkstemp's 0600 would hide outputs from others)
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


@dataclass(frozen=True)
class Fragment:
    """An .rrd file of what one node instance logged under ``entity``; ``logged``: the paths below the
    entity and the archetypes logged at each (what the recording's blueprint is built from)."""

    path: Path
    entity: str
    logged: dict[str, list[str]]
    loggers: str  # ``rerun_log.logger_digest`` when it was logged: a fragment of other loggers is not replayed


@dataclass(frozen=True)
class CacheInfo:
    directory: Path
    entries: int
    blobs: int
    bytes: int


class Cache:
    """A directory of cached node results."""

    def __init__(self, directory: str | Path):
        self.directory = Path(directory)

    def _entry_path(self, key: str) -> Path:
        return self.directory / "entries" / key[:2] / f"{key}.json"

    def _blob_path(self, digest: str) -> Path:
        return self.directory / "blobs" / digest[:2] / f"{digest}.npz"

    def _mark(self) -> None:
        marker = self.directory / MARKER
        if not marker.exists():
            atomic_write(marker, MARKER_TEXT)

    def fragment_path(self, key: str) -> Path:
        return self.directory / "rerun" / key[:2] / f"{key}.rrd"

    def capture_path(self, key: str) -> Path:
        """A fresh temporary file beside entry ``key``'s Rerun fragment, for a ``NodeCapture`` to write;
        ``store`` or ``add_fragment`` renames it into place."""
        self._mark()  # before anything else lands in the directory: `cache clear` knows it as a cache
        folder = self.fragment_path(key).parent
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{key}.rrd.", suffix=".tmp", dir=folder)
        os.close(fd)
        return Path(tmp)

    def _keep_fragment(self, key: str, fragment: Fragment) -> dict[str, Any]:
        """Move a captured fragment into place; its record for the entry. Not fsync-ed (one disk flush per
        node instance saved): a fragment torn by a crash fails its sha256 in ``fragment`` and is logged again."""
        data = fragment.path.read_bytes()
        os.chmod(fragment.path, 0o666 & ~_UMASK)
        os.replace(fragment.path, self.fragment_path(key))
        return {
            "sha256": hashlib.sha256(data).hexdigest(),
            "size": len(data),
            "entity": fragment.entity,
            "logged": fragment.logged,
            "loggers": fragment.loggers,
        }

    def add_fragment(self, key: str, fragment: Fragment) -> None:
        """Keep ``fragment`` with the existing entry ``key`` (computed without a recording: by a worker,
        or by a run with no .rrd); the entry is rewritten atomically."""
        manifest = self._manifest(key)
        manifest["rerun"] = self._keep_fragment(key, fragment)
        atomic_write(self._entry_path(key), json.dumps(manifest, sort_keys=True, indent=1).encode())

    def fragment(self, key: str, loggers: str) -> Fragment | None:
        """Entry ``key``'s Rerun fragment (None: the entry or its fragment is missing, or it was logged by other
        loggers than ``loggers``); CacheCorruption (and the fragment removed) when its bytes do not match."""
        try:
            record = self._manifest(key).get("rerun")
        except FileNotFoundError:
            return None
        if not isinstance(record, dict) or record.get("loggers") != loggers:
            return None
        path = self.fragment_path(key)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise CacheCorruption(f"Rerun fragment {path} is unreadable: {exc}") from None
        if len(data) != record.get("size") or hashlib.sha256(data).hexdigest() != record.get("sha256"):
            path.unlink(missing_ok=True)  # the entry's values are still good: only the fragment is logged again
            raise CacheCorruption(f"Rerun fragment {path} does not match its entry (truncated or edited)")
        return Fragment(path, record["entity"], record["logged"], loggers)

    def has(self, key: str) -> bool:
        """True when a complete entry for ``key`` exists (blobs present with the recorded sizes)."""
        try:
            manifest = self._manifest(key)
        except (CacheCorruption, FileNotFoundError):
            return False
        for item in manifest["outputs"].values():
            blob = self._blob_path(item["blob"])
            try:
                if blob.stat().st_size != item["size"]:
                    return False
            except FileNotFoundError:
                return False
        return True

    def _manifest(self, key: str) -> dict[str, Any]:
        path = self._entry_path(key)
        try:
            manifest = json.loads(path.read_bytes())
        except FileNotFoundError:
            raise
        except (OSError, ValueError) as exc:
            raise CacheCorruption(f"entry {path} is unreadable: {exc}") from None
        if (
            not isinstance(manifest, dict)
            or manifest.get("key") != key
            or not isinstance(manifest.get("outputs"), dict)
        ):
            raise CacheCorruption(f"entry {path} is malformed")
        return manifest

    def load(self, key: str, expected: dict[str, type]) -> dict[str, Any]:
        """Decode every output of entry ``key``; raise CacheCorruption if anything does not check out."""
        try:
            manifest = self._manifest(key)
        except FileNotFoundError:
            raise CacheCorruption(f"entry for {key} disappeared") from None
        outputs = {}
        for port, cls in expected.items():
            item = manifest["outputs"].get(port)
            if item is None:
                raise CacheCorruption(f"entry {key} lacks output '{port}'")
            path = self._blob_path(item["blob"])
            try:
                data = path.read_bytes()
            except OSError as exc:
                raise CacheCorruption(f"blob {path} is unreadable: {exc}") from None
            if hashlib.sha256(data).hexdigest() != item["blob"]:
                path.unlink(missing_ok=True)  # content-addressed: bytes that miss their name are garbage
                raise CacheCorruption(f"blob {path} does not match its hash (truncated or edited)")
            try:
                outputs[port] = codec.decode(data, cls)
            except codec.DecodeError as exc:
                raise CacheCorruption(f"blob {path} cannot be decoded: {exc}") from None
        return outputs

    def store(
        self,
        key: str,
        outputs: dict[str, Any],
        node_id: str,
        node_type: str,
        seconds: float | None = None,
        fragment: Fragment | None = None,
    ) -> None:
        """Store a node's outputs atomically: blobs (and the Rerun ``fragment``) first, then the entry that
        makes them visible. ``seconds``, the node's wall time when it ran, is kept beside them (a sweep
        reports it for points already cached)."""
        self._mark()
        manifest = {"key": key, "node": node_id, "type": node_type, "outputs": {}}
        if seconds is not None:
            manifest["seconds"] = round(float(seconds), 6)
        for port, value in outputs.items():
            data = codec.encode(value)
            digest = hashlib.sha256(data).hexdigest()
            blob = self._blob_path(digest)
            if not (blob.exists() and blob.stat().st_size == len(data)):
                atomic_write(blob, data)
            manifest["outputs"][port] = {"blob": digest, "size": len(data)}
        if fragment is not None:
            manifest["rerun"] = self._keep_fragment(key, fragment)
        atomic_write(self._entry_path(key), json.dumps(manifest, sort_keys=True, indent=1).encode())

    def recorded_seconds(self, key: str) -> float | None:
        """The wall time the node took when entry ``key`` was computed (None: unknown or no entry)."""
        try:
            value = self._manifest(key).get("seconds")
        except (CacheCorruption, FileNotFoundError):
            return None
        return float(value) if isinstance(value, (int, float)) else None

    def discard(self, key: str) -> None:
        """Forget entry ``key`` (its blobs may be shared, so they stay until ``clear``)."""
        self._entry_path(key).unlink(missing_ok=True)

    def info(self) -> CacheInfo:
        entries = list((self.directory / "entries").glob("*/*.json"))
        blobs = list((self.directory / "blobs").glob("*/*.npz"))
        fragments = list((self.directory / "rerun").glob("*/*.rrd"))
        size = sum(p.stat().st_size for p in entries + blobs + fragments)
        return CacheInfo(self.directory, len(entries), len(blobs), size)

    def is_cache(self) -> bool:
        """True when the directory carries the marker a nodegraph cache writes."""
        try:
            if (self.directory / MARKER).read_bytes().startswith(MARKER_TEXT):
                return True
            names = {p.name for p in self.directory.iterdir()}
        except OSError:
            return False
        return bool(names) and names <= {"entries", "blobs", "checkpoints"}  # written before the marker existed

    def clear(self) -> None:
        """Remove the entries, the blobs and the marker, then the directory if nothing else is left in it.
        Refuses (NodegraphError, nothing removed) a directory that is not a nodegraph cache."""
        if not self.directory.exists():
            return
        if not self.directory.is_dir():
            raise NodegraphError(f"{self.directory} is a file, not a cache directory; nothing removed")
        if not self.is_cache():
            raise NodegraphError(
                f"{self.directory} is not a nodegraph cache (it has no {MARKER} written by nodegraph); "
                "nothing removed. Give --cache-dir the cache directory itself"
            )
        failed = []
        for part in ("entries", "blobs", "rerun", "checkpoints", MARKER):
            target = self.directory / part
            try:
                if target.is_dir():
                    shutil.rmtree(target, onerror=lambda _f, path, exc: failed.append((path, exc[1])))
                elif target.exists():
                    target.unlink()
            except OSError as exc:
                failed.append((target, exc))
        if failed:
            path, exc = failed[0]
            raise NodegraphError(
                f"cannot remove {path}: {getattr(exc, 'strerror', None) or exc} "
                f"({len(failed)} path(s) left; is the directory read-only?)"
            )
        try:
            self.directory.rmdir()  # only if empty: a user's files put beside the cache stay
        except OSError:
            pass
