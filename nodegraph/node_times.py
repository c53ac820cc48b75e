"""How long each node of a recipe took when it last ran (and when it was last loaded from the cache), kept in the
cache folder: a run's progress bar expects each instance to take that long again, so its ETA comes from time, not
from the count of instances done (``report.remaining_seconds``)."""

from __future__ import annotations

import json
from pathlib import Path

from .cache import atomic_write

FILE = "node_times.json"  # removed by `nodegraph cache clear` (``Cache.clear``)
LOADED = 0.05  # seconds a cached instance is expected to take to load when no earlier load was timed


def load(directory: Path, recipe: str) -> dict[str, dict[str, float]]:
    """{node label: {"ran": seconds, "cached": seconds}} of ``recipe``'s last runs; empty when none is kept."""
    try:
        kept = json.loads((directory / FILE).read_bytes()).get(recipe, {})
        return kept if isinstance(kept, dict) else {}
    except (OSError, ValueError, AttributeError):
        return {}


def remember(directory: Path, recipe: str, records) -> None:
    """Keep the seconds of each record (``report.NodeRecord``) that ran or was loaded, by recipe and node label."""
    if not records or not directory.is_dir():
        return
    try:
        everything = json.loads((directory / FILE).read_bytes())
        if not isinstance(everything, dict):
            everything = {}
    except (OSError, ValueError):
        everything = {}
    times = everything.setdefault(recipe, {})
    for record in records:
        if record.status in ("ran", "cached"):
            times.setdefault(record.node, {})[record.status] = round(float(record.seconds), 4)
    try:
        atomic_write(directory / FILE, json.dumps(everything, sort_keys=True).encode(), durable=False)
    except OSError:  # a read-only cache: no ETA from time next run, nothing else lost
        pass


def expected(times: dict[str, dict[str, float]], label: str, cached: bool) -> float | None:
    """Seconds an instance is expected to take: its last load or run; None when it never ran."""
    kept = times.get(label, {})
    if cached:
        return kept.get("cached", LOADED)
    return kept.get("ran")
