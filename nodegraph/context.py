"""What a running node receives besides its inputs and parameters: seed, effects, progress, Rerun."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import NodegraphError


class ProgressTask:
    """A unit counter a long node advances (per frame, per element); no-op unless a reporter listens."""

    def __init__(self, callback=None):
        self._callback = callback

    def advance(self, amount: int = 1) -> None:
        if self._callback is not None:
            self._callback(amount)


class LogIndex:
    """What a run logged: entity path → the archetype names logged there (what the recording's
    blueprint is built from)."""

    def __init__(self):
        self.archetypes: dict[str, set[str]] = {}

    def add(self, path: str, archetype: str) -> None:
        self.archetypes.setdefault(path, set()).add(archetype)

    def relative(self, entity: str) -> dict[str, list[str]]:
        """The paths at or below ``entity``, relative to it (``""``: the entity itself), as stored with
        a node's cache entry."""
        cut = len(entity)
        return {
            path[cut:]: sorted(kinds)
            for path, kinds in sorted(self.archetypes.items())
            if path == entity or path.startswith(entity + "/")
        }

    def add_relative(self, entity: str, logged: dict[str, list[str]]) -> None:
        """Merge what ``relative`` gave, placed under ``entity``."""
        for sub, kinds in logged.items():
            self.archetypes.setdefault(entity + sub, set()).update(kinds)


class EntityLogger:
    """Rerun logging confined to an entity subtree; inert when no recording. ``index`` (optional)
    notes every path logged, for the blueprint."""

    def __init__(self, recording: Any | None, prefix: str, index: LogIndex | None = None):
        self.recording = recording
        self.prefix = prefix.rstrip("/")
        self.index = index

    @property
    def enabled(self) -> bool:
        return self.recording is not None

    def path(self, sub: str) -> str:
        sub = sub.strip("/")
        return f"{self.prefix}/{sub}" if sub else self.prefix

    def child(self, sub: str) -> EntityLogger:
        """A logger for the subtree ``sub`` below this one (same recording and index)."""
        return EntityLogger(self.recording, self.path(sub), self.index)

    def log(self, sub: str, archetype: Any, static: bool = False) -> None:
        if self.recording is not None:
            path = self.path(sub)
            self.recording.log(path, archetype, static=static)
            if self.index is not None:
                self.index.add(path, type(archetype).__name__)

    def set_time(self, timeline: str, sequence: int) -> None:
        if self.recording is not None:
            self.recording.set_time(timeline, sequence=sequence)

    def reset_time(self) -> None:
        if self.recording is not None:
            self.recording.reset_time()

    def send_columns(self, sub: str, indexes: list, columns: Any, archetype: str = "Scalars") -> None:
        """A whole series at once (``archetype`` names what the columns hold, for the blueprint)."""
        if self.recording is not None:
            path = self.path(sub)
            self.recording.send_columns(path, indexes=indexes, columns=columns)
            if self.index is not None:
                self.index.add(path, archetype)


class CostLimitExceeded(NodegraphError):
    """A node's own estimate of its run time is over the run's limit: refused before the work starts."""


EXPECTED_SAID_S = 10.0  # a node's own estimate at least this long is said as it starts


def format_seconds(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


@dataclass
class Context:
    """Per-run facts for one node instance. ``effects`` holds only requested effects the node implements."""

    node_id: str
    node_type: str
    seed: int | None = None
    effects: frozenset[str] = frozenset()
    variant: int | None = None
    rerun: EntityLogger = field(default_factory=lambda: EntityLogger(None, "/"))
    reporter: Any = None
    max_seconds: float | None = None  # a node expecting to run longer refuses to start (``expect_cost``)
    checkpoint: Any = None  # ``checkpoint.Checkpoint`` for resumable long nodes, None without a cache
    warnings: list[str] = field(default_factory=list)  # said by ``warn``
    _rng: np.random.Generator | None = field(default=None, repr=False)
    _estimate: tuple[float, str] | None = field(default=None, repr=False)  # said once the resumed frame is known

    @classmethod
    def standalone(cls, node_type: str = "test", seed: int | None = 0, effects=(), variant=None) -> Context:
        """A context outside any recipe: what ``NodeSpec.call`` gives a node, or a test that builds its own."""
        return cls(node_id=node_type, node_type=node_type, seed=seed, effects=frozenset(effects), variant=variant)

    def warn(self, message: str) -> None:
        """The engine's warning channel: ``message`` is said once in the run's output, as a warning of this node
        (a user's file repaired: the file and what changed), and kept with its cached result, so a run that loads
        the result says it too; what the recipe alone decides is declared for ``nodegraph check`` too
        (``node.warns_of``)."""
        if message not in self.warnings:
            self.warnings.append(message)

    @property
    def rng(self) -> np.random.Generator:
        """The node's random generator, seeded from the recipe seed, node id and variant."""
        if self.seed is None:
            raise NodegraphError(
                f"node type '{self.node_type}' draws random numbers but is not declared random=True "
                "(its cache key would ignore the seed)"
            )
        if self._rng is None:
            self._rng = np.random.default_rng(self.seed)
        return self._rng

    def expect_cost(self, seconds: float, what: str) -> None:
        """Called by a long node before its work, with its estimate: said when it is long (≥ 10 s), and
        refused (CostLimitExceeded) when over ``max_seconds``, so a parameter that makes a run take hours
        is caught before the hours, not after; nodes upstream stay cached."""
        label = self.node_id if self.variant is None else f"{self.node_id}[{self.variant}]"
        if self.max_seconds is not None and seconds > self.max_seconds:
            raise CostLimitExceeded(
                f"{what} would take ≈ {format_seconds(seconds)}, over this run's limit of "
                f"{format_seconds(self.max_seconds)}: run again with --yes to go ahead (or --max-minutes N); "
                "the nodes before it are cached"
            )
        if self.checkpoint is not None and self.checkpoint.path.exists():
            # a resumed run: said as its progress starts (``progress``), for the steps left after the checkpoint's
            self._estimate = (seconds, what)
        elif seconds >= EXPECTED_SAID_S and self.reporter is not None:
            self.reporter.info(f"{label}: {what}, ≈ {format_seconds(seconds)} expected")

    def _say_estimate(self, total: int) -> None:
        """The estimate ``expect_cost`` held back for a saved checkpoint: the share of the ``total`` steps that
        the checkpoint (its ``frames_done``, in the steps of the node's progress) leaves, all of it where the
        checkpoint could not be read."""
        seconds, what = self._estimate
        self._estimate = None
        done = getattr(self.checkpoint, "steps_done", None)
        label = self.node_id if self.variant is None else f"{self.node_id}[{self.variant}]"
        if isinstance(done, int) and 0 < done <= total:
            seconds *= (total - done) / total
            what += f"; {total - done:,} of {total:,} left after the checkpoint"
        if seconds >= EXPECTED_SAID_S and self.reporter is not None:
            self.reporter.info(f"{label}: {what}, ≈ {format_seconds(seconds)} expected")

    def wants(self, effect: str) -> bool:
        """True when the recipe asked for ``effect`` (and this node implements it)."""
        return effect in self.effects

    @contextlib.contextmanager
    def progress(self, total: int, description: str = "") -> Iterator[ProgressTask]:
        """A progress bar of ``total`` steps for this node, shown while the block runs."""
        if self._estimate is not None:
            self._say_estimate(total)
        if self.reporter is None:
            yield ProgressTask()
            return
        label = self.node_id if self.variant is None else f"{self.node_id}[{self.variant}]"
        with self.reporter.task(f"{label} {description}".strip(), total) as callback:
            yield ProgressTask(callback)
