"""Resumable work for long nodes: a node saves its progress now and then; a re-run of the same
node instance (same cache key: same code, libraries, inputs, parameters, seed, effects) starts from there.

The checkpoint sits in the cache directory (``checkpoints/<key>.npz``), written atomically with the
value codec, so an interrupted run (Ctrl-C, SIGTERM, a lost machine) loses at most ``interval``
seconds of work; the engine deletes it when the node completes.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from . import codec, interrupt
from .cache import atomic_write


class Checkpoint:
    """One node instance's saved progress (any value the codec stores)."""

    def __init__(self, path: Path, interval: float = 30.0):
        self.path = Path(path)
        self.interval = interval
        self._last = time.monotonic()
        self.steps_done: int | None = None  # what ``load`` resumed from: the saved ``frames_done``, if any

    def due(self) -> bool:
        """True when ``interval`` seconds have passed since the last save (or since the node started)."""
        return time.monotonic() - self._last >= self.interval

    def save(self, value: Any) -> None:
        """Save ``value``; one with a ``frames_done`` count (in the steps of the node's ``ctx.progress``) is named by
        it where a stopped run says what a re-run resumes from, and a resumed run's estimate counts the steps left."""
        atomic_write(self.path, codec.encode(value))
        self._last = time.monotonic()
        done = getattr(value, "frames_done", None)
        interrupt.progress_saved(self.path, f"frame {done:,}" if isinstance(done, int) else "")

    def load(self) -> Any | None:
        """The saved progress with writable arrays, or None (none saved, or unreadable: then removed)."""
        try:
            data = self.path.read_bytes()
        except OSError:
            return None
        try:
            value = codec.thaw(codec.decode(data))
        except codec.DecodeError:
            self.clear()
            return None
        done = getattr(value, "frames_done", None)
        self.steps_done = done if isinstance(done, int) else None  # the estimate said on resume counts the rest
        return value

    def clear(self) -> None:
        self.path.unlink(missing_ok=True)
