"""What a sweep is, before it runs: a grid of parameter values, fixed overrides, metrics to read.

A recipe declares its sweeps in a ``sweeps:`` block, validated with the rest of the recipe (every
problem with file:line:column); ``nodegraph sweep --grid/--metric`` builds the same declaration from
the command line::

    sweeps:
      substeps:                              # nodegraph sweep R.yaml --sweep substeps
        doc: accuracy of the solver against its cost
        grid:                                # every combination is one run (first key varies slowest)
          sim.substeps: [2, 4, 8, 16]
          sim.iterations: [1, 2]
        set: {sim.frames: 10}                # overrides shared by every point
        metrics: [measure.stats.penetration_max]   # node.port[.column][:last|first|min|max|mean|sum][:higher]
        outputs: [sim.state]                 # also pulled (default: the metrics' nodes, else the outputs)
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field

AGGREGATES = ("last", "first", "min", "max", "mean", "sum")
DIRECTIONS = ("lower", "higher")  # which way a metric is better: an error lower, a count of elements higher


class SweepModel(BaseModel):
    """One entry of a recipe's ``sweeps:`` block."""

    model_config = ConfigDict(extra="forbid")
    doc: str | None = None
    grid: dict[str, list[Any]] = Field(min_length=1)
    set: dict[str, Any] = Field(default_factory=dict)
    metrics: list[str] = Field(default_factory=list)
    outputs: list[str] = Field(default_factory=list)


@dataclass(frozen=True)
class MetricRef:
    """A number read from a Table output: ``node.port[.column][:aggregate][:higher]`` (default: the last row;
    lower is better unless ``:higher``, e.g. for a count of placed elements)."""

    node: str
    port: str
    column: str | None = None
    aggregate: str = "last"
    higher: bool = False

    @property
    def name(self) -> str:
        text = ".".join(p for p in (self.node, self.port, self.column) if p)
        return text if self.aggregate == "last" else f"{text}:{self.aggregate}"


def parse_metric(text: str) -> MetricRef:
    """``node.port[.column][:aggregate][:higher|:lower]``; a ValueError says what is expected."""
    ref, *options = str(text).split(":")
    parts = ref.split(".")
    if len(parts) not in (2, 3) or not all(parts):
        raise ValueError("expected node.port or node.port.column (a Table output), optionally :aggregate")
    aggregate, direction = "last", "lower"
    for option in options:
        if not option:
            continue
        if option in AGGREGATES:
            aggregate = option
        elif option in DIRECTIONS:
            direction = option
        else:
            raise ValueError(
                f"unknown aggregate '{option}' (aggregates: {', '.join(AGGREGATES)}; which way is better: "
                f"{', '.join(DIRECTIONS)})"
            )
    return MetricRef(parts[0], parts[1], parts[2] if len(parts) == 3 else None, aggregate, direction == "higher")


def parse_grid(text: str) -> tuple[str, list[Any]]:
    """``node.param=v1,v2,…`` (each value YAML, e.g. ``[1,2],[3,4]`` for list values)."""
    if "=" not in text:
        raise ValueError("expected node.param=v1,v2,...")
    target, _, raw = text.partition("=")
    try:
        values = yaml.safe_load(f"[{raw}]")
    except yaml.YAMLError as exc:
        raise ValueError(f"cannot read the values: {exc}") from None
    if not target.strip() or not values or any(v is None for v in values):
        raise ValueError("expected node.param=v1,v2,... with at least one value")
    return target.strip(), values


def override_text(target: str, value: Any) -> str:
    """A ``--set`` text for one value (JSON is YAML, so every value reads back as itself)."""
    return f"{target}={json.dumps(value)}"


@dataclass(frozen=True)
class SweepDecl:
    """A validated sweep: the grid axes in order, the shared overrides, the metrics, extra outputs."""

    name: str
    grid: tuple[tuple[str, tuple[Any, ...]], ...]
    fixed: tuple[str, ...] = ()
    metrics: tuple[MetricRef, ...] = ()
    outputs: tuple[str, ...] = ()
    doc: str = ""

    def points(self) -> list[dict[str, Any]]:
        """Every combination of the grid's values, the first axis varying slowest."""
        axes = [target for target, _ in self.grid]
        return [dict(zip(axes, combo)) for combo in itertools.product(*(values for _, values in self.grid))]


def check_sweeps(validator, raw_sweeps: dict, entries: dict, raw_nodes: dict) -> dict[str, SweepDecl]:
    """Validate a recipe's ``sweeps:`` block against its nodes; issues go to ``validator.issue``."""
    from pydantic import ValidationError

    from .params import ParamValueError

    sweeps: dict[str, SweepDecl] = {}
    if not isinstance(raw_sweeps, dict):
        validator.issue(("sweeps",), "sweeps must be a mapping of sweep name → {grid, set, metrics, outputs, doc}")
        return sweeps
    for name, body in raw_sweeps.items():
        base = ("sweeps", name)
        try:
            model = SweepModel.model_validate(body if body is not None else {})
            ok = True
        except ValidationError as exc:
            validator.pydantic_issues(exc, base, None, SweepModel)
            known = {k: v for k, v in body.items() if k in SweepModel.model_fields} if isinstance(body, dict) else {}
            try:  # an unknown key alone: the rest is still checked, so every problem is reported at once
                model = SweepModel.model_validate(known)
            except ValidationError:
                continue
            ok = False

        def check_target(target: str, values: list, path: tuple, one_value: bool) -> bool:
            if target == "seed":
                bad = [v for v in values if not isinstance(v, int) or isinstance(v, bool)]
                if bad:
                    validator.issue(path, "seed takes whole numbers", param="seed", given=bad[0])
                return not bad
            node_id, _, key = target.partition(".")
            if not key or "." in key:
                validator.issue(path, f"cannot read '{target}'", key=True, allowed="node.param or seed")
                return False
            if node_id not in entries:
                if node_id not in raw_nodes:
                    validator.issue(
                        path,
                        f"no node '{node_id}' in the recipe",
                        key=True,
                        given=target,
                        suggestion=_nearest(node_id, raw_nodes),
                    )
                return False
            spec = entries[node_id].spec
            if key in ("variants", "seed"):
                bad = [
                    v for v in values if not isinstance(v, int) or isinstance(v, bool) or (v < 1 and key == "variants")
                ]
                if bad:
                    validator.issue(path, f"{key} takes whole numbers", node=node_id, param=key, given=bad[0])
                return not bad
            param = spec.params.get(key)
            if param is None:
                validator.issue(
                    path,
                    f"unknown parameter '{key}' for {spec.type_name}",
                    key=True,
                    node=node_id,
                    allowed=", ".join(spec.params) or "(none)",
                    suggestion=_nearest(key, spec.params),
                )
                return False
            good = True
            for i, value in enumerate(values):
                try:
                    param.validate(value, base=validator.base_dir)
                except ParamValueError as exc:
                    where = path if one_value else path + (i,)
                    validator.issue(where, str(exc), node=node_id, param=key, given=value, allowed=exc.allowed)
                    good = False
            return good

        for target, values in model.grid.items():
            if not values:
                validator.issue(base + ("grid", target), "a grid axis needs at least one value", param=target)
                ok = False
                continue
            ok &= check_target(str(target), values, base + ("grid", target), False)
        for target, value in model.set.items():
            ok &= check_target(str(target), [value], base + ("set", target), True)
        metrics = []
        for i, text in enumerate(model.metrics):
            problem = metric_problem(text, entries, raw_nodes)
            if problem is not None:
                validator.issue(base + ("metrics", i), problem[0], given=text, suggestion=problem[1])
                ok = False
            else:
                metrics.append(parse_metric(text))
        for i, text in enumerate(model.outputs):
            node_id, _, port = text.partition(".")
            if node_id not in entries or (port and port not in entries[node_id].spec.outputs):
                validator.issue(base + ("outputs", i), f"no output '{text}' in the recipe", given=text)
                ok = False
        if ok:
            sweeps[str(name)] = SweepDecl(
                str(name),
                tuple((str(t), tuple(v)) for t, v in model.grid.items()),
                tuple(override_text(str(t), v) for t, v in model.set.items()),
                tuple(metrics),
                tuple(model.outputs),
                model.doc or "",
            )
    return sweeps


def metric_problem(text: str, entries: dict, raw_nodes: dict = ()) -> tuple[str, str | None] | None:
    """Why ``text`` is not a metric of this recipe (message, suggestion), or None when it is."""
    from .values import Table

    try:
        ref = parse_metric(text)
    except ValueError as exc:
        return str(exc), None
    if ref.node not in entries:
        return None if ref.node in raw_nodes else (f"no node '{ref.node}' in the recipe", _nearest(ref.node, entries))
    outputs = entries[ref.node].spec.outputs
    tables = [p for p, out in outputs.items() if issubclass(out.type, Table)]
    if ref.port not in outputs or ref.port not in tables:
        what = (
            f"'{ref.node}' has no output '{ref.port}'"
            if ref.port not in outputs
            else f"'{ref.node}.{ref.port}' is not a Table"
        )
        allowed = ", ".join(f"{ref.node}.{p}" for p in tables) or "none: that node has no Table output"
        return f"{what}; metrics are read from Table outputs ({allowed})", _nearest(ref.port, tables)
    columns = outputs[ref.port].columns  # where declared: the column too, before the sweep's work
    if ref.column is not None and columns and ref.column not in columns:
        return (
            f"'{ref.node}.{ref.port}' has no column '{ref.column}'; its columns: {', '.join(columns)}",
            _nearest(ref.column, columns),
        )
    return None


def _nearest(word, options) -> str | None:
    import difflib

    matches = difflib.get_close_matches(str(word), [str(o) for o in options], n=1, cutoff=0.5)
    return matches[0] if matches else None
