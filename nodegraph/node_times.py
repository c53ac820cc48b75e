"""How long each node of a recipe took when it last ran (and when it was last loaded from the cache), kept in the
cache folder: a run's progress bar expects each instance to take that long again, so its ETA comes from time, not
from the count of instances done (``report.remaining_seconds``); a node that never ran is expected to take what the
recipe's cost estimate says (``planned``), and where nothing says, the bar shows no ETA rather than a count's."""

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


def planned(instances, times: dict[str, dict[str, float]], estimate=None) -> list[float | None]:
    """Seconds each of ``instances`` ((node id, label, cached) in run order) is expected to take: its last time
    (``expected``), else the estimate's (``cost.Estimate``): a node's own seconds where it estimates them, and an
    even share of the rest (``Estimate.other_seconds``) among the instances to run that do not; None where neither
    says (no estimate: a recipe run without ``check``'s weighing)."""
    plan = [expected(times, label, cached) for _, label, cached in instances]
    if estimate is None:
        return plan
    own = {node: cost.seconds for node, cost in estimate.costs.items() if cost.seconds > 0}
    rest = [i for i, (node, _, cached) in enumerate(instances) if plan[i] is None and node not in own]
    share = estimate.other_seconds / len(rest) if rest else 0.0
    for i, (node, _, _) in enumerate(instances):
        if plan[i] is None:
            plan[i] = own.get(node, share)
    return plan
