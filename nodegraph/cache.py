"""Content-addressed result cache: entries by cache key, output blobs by the sha256 of their bytes.

Layout under the cache directory::

    CACHEDIR.TAG            marks the directory as a nodegraph cache (https://bford.info/cachedir/)
    entries/ab/<key>.json   {"key", "node", "type", "outputs": {port: {"blob": sha, "size": n}}}
    blobs/cd/<sha>.npz      one encoded value (see ``codec``), deflated; identical outputs are stored once
    rerun/ab/<key>.rrd      what the node logged to Rerun (as it ran, then its outputs): replayed into
                            a cached re-run's recording instead of logging the values again
    checkpoints/<key>.npz   a long node's progress while it runs (``checkpoint``), removed when it completes
    runs/<hash>.json        {"run", "keys"}: the entries the latest run of a recipe used (``keep_run``)
    limit                   the size limit in bytes (``nodegraph cache limit SIZE``), if one was set

An entry's modification time is when it was last stored or loaded. Above the size limit (``limit``: the
``$NODEGRAPH_CACHE_LIMIT`` environment variable, else the ``limit`` file, else ``DEFAULT_LIMIT``) ``evict``
removes the least recently used entries, their Rerun fragments and the blobs no remaining entry names; the CLI
calls it when a run ends, sparing what that run used. Entries the latest run of some recipe used go only after
every other entry (an hour of drafts and sweeps of other recipes no longer evicts the main job's last run).

Every file is written to a temporary name in its final directory and renamed into place, blobs and the Rerun
fragment before the entry that names them, so a crash of the process at any moment leaves either no entry or a
whole one (entries and blobs are not flushed to disk: after an OS crash or a power loss one may be torn, and then
fails its check as it is read and is recomputed); eviction removes an entry before its files, so a reader sees a
whole entry or none, and an entry whose blob went missing is recomputed (a fragment is checked against the sha256
its entry records before it is replayed). A blob whose bytes no longer hash to its name is reported as corruption
and recomputed. ``clear`` removes only what a cache holds, and only from a directory carrying the marker.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import codec, interrupt
from .errors import CacheCorruption, NodegraphError

DEFAULT_DIR = ".nodegraph/cache"  # before issue 47: in the current folder; still used where one exists
ENV_VAR = "NODEGRAPH_CACHE"
LIMIT_ENV_VAR = "NODEGRAPH_CACHE_LIMIT"
LIMIT_FILE = "limit"
DEFAULT_LIMIT = 2 * 2**30  # 2 GiB: a few full-size runs of the main job (≈ 150 MiB of entries each) and many drafts
_UNITS = {"": 1, "b": 1, "k": 2**10, "kib": 2**10, "m": 2**20, "mib": 2**20, "g": 2**30, "gib": 2**30}


MARKER = "CACHEDIR.TAG"
MARKER_TEXT = (
    b"Signature: 8a477f597d28d172789f06886806bc55\n"
    b"# This directory is a nodegraph cache: `nodegraph cache clear` empties it.\n"
)
_UMASK = os.umask(0)
os.umask(_UMASK)


def default_cache_dir() -> Path:
    """``$NODEGRAPH_CACHE``, else the user's cache folder (``$XDG_CACHE_HOME`` or ``~/.cache``, then
    ``nodegraph/cache``, beside the kernels' ``nodegraph/numba``): one cache whichever folder a command runs in.
    A cache an earlier version made in ``.nodegraph/cache`` of the current folder is still used there (its
    results stay warm) until it is moved or cleared."""
    if os.environ.get(ENV_VAR):
        return Path(os.environ[ENV_VAR])
    if (Path(DEFAULT_DIR) / MARKER).is_file():
        return Path(DEFAULT_DIR)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "nodegraph" / "cache"


def check_writable(directory: Path, what: str, fix: str) -> list[Path]:
    """Fail before any compute when ``directory`` cannot be created or written (read-only disk, a file
    in the way), naming the path and ``fix``. Returns the folders it made, outermost first, each named to a
    supervisor (``interrupt.note``), which removes those a stopped run left empty."""
    made = [d for d in (directory, *directory.parents) if not d.exists()][::-1]
    try:
        directory.mkdir(parents=True, exist_ok=True)
        for folder in made:
            interrupt.note(folder.resolve())
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
    return made


def atomic_write(path: Path, data: bytes, durable: bool = True) -> None:
    """Write ``data`` to ``path`` so that readers see the old file or the whole new one, never a part.
    ``durable``: on disk before the rename (a flush that costs ≈ 10 ms a file, more for a large one); the cache
    passes False for what it checks as it reads (a blob's sha256, an entry's JSON and key): what a crash
    tears there is found and computed again."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    interrupt.note(tmp)  # removed by a supervising parent if this process is killed before the rename
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)  # as open() would make it (mkstemp's 0600 would hide outputs from others)
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            if durable:
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


def parse_size(text: str, what: str = "cache limit") -> int:
    """Bytes from ``500MiB``, ``2 GiB``, ``1.5G``, ``800k`` or a plain number of bytes (binary units)."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*([A-Za-z]*)\s*", str(text))
    unit = match.group(2).lower() if match else ""
    if match is None or unit not in _UNITS:
        raise NodegraphError(f"{what}: '{text}' is not a size; give bytes or a number with KiB, MiB or GiB (e.g. 2GiB)")
    return int(float(match.group(1)) * _UNITS[unit])


def format_size(n: int) -> str:
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{n} B"


@dataclass(frozen=True)
class CacheInfo:
    directory: Path
    entries: int
    blobs: int
    bytes: int


@dataclass(frozen=True)
class Eviction:
    """What ``evict`` did: entries removed, bytes freed, bytes left, whether what was spared alone is above the
    limit, the node of each entry removed, and the runs (``keep_run``) whose latest entries it removed."""

    entries: int
    freed: int
    left: int
    over: bool
    nodes: tuple[str, ...] = ()
    runs: tuple[str, ...] = ()


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
        interrupt.note(tmp)
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
        atomic_write(self._entry_path(key), json.dumps(manifest, sort_keys=True, indent=1).encode(), durable=False)

    def fragment(self, key: str, loggers: str | None) -> Fragment | None:
        """Entry ``key``'s Rerun fragment (None: the entry or its fragment is missing, or it was logged by other
        loggers than ``loggers``; ``loggers`` None: by any); CacheCorruption (and the fragment removed) when its
        bytes do not match."""
        try:
            record = self._manifest(key).get("rerun")
        except FileNotFoundError:
            return None
        if not isinstance(record, dict) or (loggers is not None and record.get("loggers") != loggers):
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
        return Fragment(path, record["entity"], record["logged"], record.get("loggers"))

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
        self.touch(key)
        return outputs

    def touch(self, key: str) -> None:
        """Mark entry ``key`` used now (its modification time): the last to go when the cache is trimmed."""
        try:
            os.utime(self._entry_path(key))
        except OSError:  # gone (evicted by another run) or read-only: the value in hand is still good
            pass

    def store(
        self,
        key: str,
        outputs: dict[str, Any],
        node_id: str,
        node_type: str,
        seconds: float | None = None,
        fragment: Fragment | None = None,
        quick: bool = False,
        warnings: list[str] = (),
    ) -> None:
        """Store a node's outputs atomically: blobs (and the Rerun ``fragment``) first, then the entry that
        makes them visible. ``seconds``, the node's wall time when it ran, is kept beside them (a sweep
        reports it for points already cached). ``quick``, or a stop waiting for the store (``interrupt.pending``):
        blobs not deflated, written in a fraction of the time (a stop has ``interrupt.HOLD_MAX`` seconds).
        ``warnings``: what the node warned of (``Context.warn``), said again by a run that loads the entry."""
        self._mark()
        manifest = {"key": key, "node": node_id, "type": node_type, "outputs": {}}
        if seconds is not None:
            manifest["seconds"] = round(float(seconds), 6)
        if warnings:
            manifest["warnings"] = list(warnings)
        for port, value in outputs.items():
            # deflated: a run's outputs ≈ 44 % smaller on disk
            data = codec.encode(value, compress=not (quick or interrupt.pending()))
            digest = hashlib.sha256(data).hexdigest()
            blob = self._blob_path(digest)
            if not (blob.exists() and blob.stat().st_size == len(data)):
                atomic_write(blob, data, durable=False)
            manifest["outputs"][port] = {"blob": digest, "size": len(data)}
        if fragment is not None:
            manifest["rerun"] = self._keep_fragment(key, fragment)
        atomic_write(self._entry_path(key), json.dumps(manifest, sort_keys=True, indent=1).encode(), durable=False)

    def warnings(self, key: str) -> list[str]:
        """What the node warned of when entry ``key`` was computed (``Context.warn``); [] for none or no entry."""
        try:
            said = self._manifest(key).get("warnings")
        except (CacheCorruption, FileNotFoundError):
            return []
        return [str(w) for w in said] if isinstance(said, list) else []

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

    def limit(self) -> int:
        """The size limit in bytes: ``$NODEGRAPH_CACHE_LIMIT``, else the cache's ``limit`` file, else
        ``DEFAULT_LIMIT``."""
        if os.environ.get(LIMIT_ENV_VAR):
            return parse_size(os.environ[LIMIT_ENV_VAR], f"${LIMIT_ENV_VAR}")
        try:
            return parse_size((self.directory / LIMIT_FILE).read_text(), str(self.directory / LIMIT_FILE))
        except FileNotFoundError:
            return DEFAULT_LIMIT

    def set_limit(self, limit: int) -> None:
        """Keep ``limit`` (bytes) in the cache's ``limit`` file (atomically)."""
        if limit <= 0:
            raise NodegraphError(f"cache limit: {limit} bytes; give a size above 0 (e.g. 2GiB)")
        self._mark()
        atomic_write(self.directory / LIMIT_FILE, f"{limit}\n".encode())

    def _run_path(self, run: str) -> Path:
        return self.directory / "runs" / f"{hashlib.sha256(run.encode()).hexdigest()[:16]}.json"

    def keep_run(self, run: str, keys) -> None:
        """Record ``keys`` as the entries the latest run called ``run`` (a recipe file, draft or not) used,
        replacing that run's earlier record: ``evict`` takes them last."""
        self._mark()
        (self.directory / "runs").mkdir(exist_ok=True)
        atomic_write(self._run_path(run), json.dumps({"run": run, "keys": sorted(set(keys))}).encode(), durable=False)

    def latest_runs(self) -> set[str]:
        """The keys the latest run of each recipe used (``keep_run``)."""
        return set().union(*self.latest_run_keys().values())

    def latest_run_keys(self) -> dict[str, set[str]]:
        """{run: the keys it used} of the latest run of each recipe (``keep_run``)."""
        kept: dict[str, set[str]] = {}
        for path in (self.directory / "runs").glob("*.json"):
            try:
                record = json.loads(path.read_bytes())
                kept[str(record["run"])] = set(record["keys"])
            except (OSError, ValueError, KeyError, TypeError):
                continue  # being written or damaged: its entries are plain LRU
        return kept

    def evict(self, limit: int | None = None, spare_since: float | None = None) -> Eviction:
        """Remove least recently used entries until the cache holds at most ``limit`` bytes (default
        ``self.limit()``), those a recipe's latest run used (``keep_run``) only once every other has gone;
        entries used at or after ``spare_since`` (a ``time.time()``: the run that just ended) stay even above it.
        An entry goes first (readers then miss it), then its Rerun fragment, then each blob that no remaining
        entry names."""
        limit = self.limit() if limit is None else limit
        total = self.info().bytes
        if total <= limit:  # the usual case, known from file sizes alone: no entry need be read
            return Eviction(0, 0, total, False)
        entries = []
        for path in (self.directory / "entries").glob("*/*.json"):
            try:
                stat = path.stat()
                manifest = json.loads(path.read_bytes())
                blobs = {item["blob"] for item in manifest["outputs"].values()}
            except (OSError, ValueError, KeyError, TypeError, AttributeError):
                continue  # being written or corrupt: not ours to judge here
            entries.append((stat.st_mtime, path, stat.st_size, blobs, str(manifest.get("node", "?"))))
        blob_sizes = {}
        for blob in (self.directory / "blobs").glob("*/*.npz"):
            try:
                blob_sizes[blob.stem] = blob.stat().st_size
            except OSError:
                continue
        users: dict[str, int] = {}
        for _, _, _, blobs, _ in entries:
            for digest in blobs:
                users[digest] = users.get(digest, 0) + 1

        def fragment_size(entry: Path) -> int:
            try:
                return self.fragment_path(entry.stem).stat().st_size
            except OSError:
                return 0

        runs = self.latest_run_keys()
        latest = set().union(*runs.values())
        freed = 0
        nodes, keys = [], set()
        for mtime, path, size, blobs, node in sorted(entries, key=lambda e: (e[1].stem in latest, e[0])):
            if total - freed <= limit:
                break
            if spare_since is not None and mtime >= spare_since:
                continue
            gone = size + fragment_size(path)
            path.unlink(missing_ok=True)
            self.fragment_path(path.stem).unlink(missing_ok=True)
            for digest in blobs:
                users[digest] -= 1
                if users[digest] == 0 and digest in blob_sizes:
                    self._blob_path(digest).unlink(missing_ok=True)
                    gone += blob_sizes[digest]
            freed += gone
            nodes.append(node)
            keys.add(path.stem)
        lost = tuple(sorted(run for run, used in runs.items() if used & keys))
        return Eviction(len(nodes), freed, total - freed, total - freed > limit, tuple(nodes), lost)

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
        """Remove the entries, the blobs, the limit and the marker, then the directory if nothing else is left in it.
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
        for part in ("entries", "blobs", "rerun", "checkpoints", "runs", "node_times.json", LIMIT_FILE, MARKER):
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
