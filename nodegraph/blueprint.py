"""The Rerun blueprint of a run's recording, built from the recipe and from what the run logged.

Tabs: ``result`` (a 3D view of the last node's 3D output, the image outputs beside it), then one tab
per node family (the package a node type is declared in), with per node a 3D view of its outputs, a 3D
view of what it logged as it ran (``/<node>/log/…``, e.g. a simulation's particles per step), a
time-series view per scalar series and a view per image or text. Views are chosen from the archetypes
found at each entity path, so the engine needs to know nothing of the values themselves.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .context import LogIndex
from .recipe import Recipe

SPATIAL_3D = {"Mesh3D", "Points3D", "Arrows3D", "Boxes3D", "LineStrips3D", "Ellipsoids3D", "Asset3D"}
IMAGE = {"Image", "EncodedImage", "DepthImage", "SegmentationImage"}
SERIES = {"Scalars", "SeriesLines", "SeriesPoints"}
TEXT = {"TextDocument"}
LOG = "log"  # a node's own logging goes to /<node>[/<variant>]/log/…, its outputs to /<node>[/<variant>]/<port>


def node_family(module: str) -> str:
    """The family a node type belongs to: its package below the top one (``nodes.placement.cull`` →
    ``placement``), or the module itself for a single-file plugin."""
    parts = module.split(".")
    return parts[1] if len(parts) > 2 else parts[0]


@dataclass
class NodeLogs:
    """The entity paths one node's instances logged, sorted by what can show them."""

    outputs_3d: list[str] = field(default_factory=list)
    log_3d: list[str] = field(default_factory=list)
    series: list[str] = field(default_factory=list)
    images: list[str] = field(default_factory=list)
    texts: list[str] = field(default_factory=list)
    log_roots: list[str] = field(default_factory=list)


def _node_logs(node_id: str, index: LogIndex) -> NodeLogs:
    logs = NodeLogs()
    root = f"/{node_id}"
    for path in sorted(index.archetypes):
        if path != root and not path.startswith(root + "/"):
            continue
        parts = path[len(root) + 1 :].split("/")
        in_log = LOG in parts[:2]  # /<node>/log/… or /<node>/<variant>/log/…
        if in_log:
            log_root = "/".join([root] + parts[: parts.index(LOG) + 1])
            if log_root not in logs.log_roots:
                logs.log_roots.append(log_root)
        kinds = index.archetypes[path]
        if kinds & SPATIAL_3D:
            (logs.log_3d if in_log else logs.outputs_3d).append(path)
        if kinds & SERIES:
            logs.series.append(path)
        if kinds & IMAGE:
            logs.images.append(path)
        if kinds & TEXT and not in_log:
            logs.texts.append(path)
    return logs


def _output_subtrees(paths: list[str], node_id: str) -> list[str]:
    """The output entities (``/<node>[/<variant>]/<port>``) the given paths lie in."""
    out = []
    for path in paths:
        parts = path.split("/")  # '', node, port | variant, ...
        depth = 4 if len(parts) > 3 and parts[2].isdigit() else 3
        top = "/".join(parts[:depth])
        if top not in out:
            out.append(top)
    return out


def build_blueprint(recipe: Recipe, index: LogIndex):
    """A ``rerun.blueprint.Blueprint`` for the recording of ``recipe``'s run (None when nothing was logged)."""
    import rerun.blueprint as rrb

    order = [
        node_id
        for node_id in recipe.order()
        if any(p == f"/{node_id}" or p.startswith(f"/{node_id}/") for p in index.archetypes)
    ]
    if not order:
        return None
    logs = {node_id: _node_logs(node_id, index) for node_id in order}
    families: dict[str, list] = {}
    for node_id in order:
        node = logs[node_id]
        views = []
        if node.outputs_3d:
            views.append(
                rrb.Spatial3DView(
                    name=node_id,
                    origin="/",
                    contents=[f"+ /{node_id}/**"] + [f"- {root}/**" for root in node.log_roots],
                )
            )
        if node.log_3d:
            views.append(
                rrb.Spatial3DView(
                    name=f"{node_id}: as it ran", origin="/", contents=[f"+ {root}/**" for root in node.log_roots]
                )
            )
        # a series the node logged: a view each (a simulation's residual, energy, ...); an output
        # table's columns: one view per table
        logged = [path for path in node.series if any(path.startswith(root + "/") for root in node.log_roots)]
        views += [
            rrb.TimeSeriesView(name=f"{node_id}: {path.rsplit('/', 1)[-1]}", origin="/", contents=[f"+ {path}"])
            for path in logged
        ]
        views += [
            rrb.TimeSeriesView(name=f"{node_id}: {top[len(node_id) + 2 :]}", origin="/", contents=[f"+ {top}/**"])
            for top in _output_subtrees([p for p in node.series if p not in logged], node_id)
        ]
        views += [rrb.Spatial2DView(name=f"{node_id}: {path.rsplit('/', 1)[-1]}", origin=path) for path in node.images]
        views += [
            rrb.TextDocumentView(name=f"{node_id}: {path.rsplit('/', 1)[-1]}", origin=path) for path in node.texts
        ]
        if views:
            families.setdefault(node_family(recipe.nodes[node_id].spec.module), []).extend(views)
    tabs = []
    last_3d = next((node_id for node_id in reversed(order) if logs[node_id].outputs_3d), None)
    result = []
    if last_3d is not None:
        result.append(
            rrb.Spatial3DView(
                name=f"final scene ({last_3d})",
                origin="/",
                contents=[f"+ {top}/**" for top in _output_subtrees(logs[last_3d].outputs_3d, last_3d)],
            )
        )
    result += [
        rrb.Spatial2DView(name=path.strip("/"), origin=path)
        for node_id in order
        for path in logs[node_id].images
        if LOG not in path.split("/")
    ]
    if result:
        tabs.append(rrb.Horizontal(*result, name="result"))
    tabs += [rrb.Grid(*views, name=family) for family, views in families.items()]
    return rrb.Blueprint(rrb.Tabs(*tabs, name=recipe.name), collapse_panels=False)
