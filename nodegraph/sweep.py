"""``nodegraph sweep``: a recipe run at every point of a parameter grid, cost against measured metrics.

Each point is an ordinary run with the point's overrides, against one cache, so every node instance
the grid does not touch is computed once and shared (a sweep of a simulation knob never re-models
what is upstream of the simulation). Per point:

- ``seconds``: the wall time of the point's own node instances, those not common to every point (the
  common ones are reported once); an instance computed during the sweep counts with the time it took
  then (on whichever worker), one already cached with the time its cache entry recorded;
- metrics read from Table outputs (``sweep_decl.MetricRef``); a variant family gives the mean over
  its variants;
- the sha256 of each pulled output's stored bytes, so two sweeps (in-process, on a cluster) compare
  bit for bit.

The table is written as Markdown and CSV, and a PNG plots each metric against the time with the Pareto
front marked (lower time is better; a metric is better lower, an error, unless declared ``:higher``, e.g. a
count of elements); the recipe's own setting is marked too. Every pulled Image output (a preview) is also
laid out as a contact sheet, each tile labelled with its point's parameter values.
With ``rrd`` every point is also logged as its own recording (id from recipe and overrides), all in
one .rrd, so two settings can be scrubbed side by side in a viewer. With a pool (``pool.InstancePool``)
the instances of every point are computed by its workers first, as one task graph in which shared
instances are one task.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import codec
from .cache import Cache, atomic_write
from .contact_sheet import grid_pixels
from .errors import Issue, Location, NodegraphError, RecipeError
from .executor import resolve_outputs, run_recipe
from .plan import Instance, Plan, RecipeRef, plan_jobs
from .recipe import Recipe, load_recipe
from .report import Reporter
from .rerun_log import merge_recordings
from .sweep_decl import MetricRef, SweepDecl, override_text
from .values import Image, Table


@dataclass
class PointResult:
    """One grid point: its values, its own cost, its metrics and the hashes of its outputs."""

    values: dict[str, Any]
    overrides: tuple[str, ...]
    seconds: float | None
    ran: int
    cached: int
    metrics: dict[str, float]
    hashes: dict[str, str]
    recipe_setting: bool = False
    images: dict[str, np.ndarray] = field(default_factory=dict)  # pulled Image outputs' pixels, by output

    @property
    def digest(self) -> str:
        """One sha256 over the point's output hashes (what two sweeps compare)."""
        return hashlib.sha256(" ".join(f"{k}={v}" for k, v in sorted(self.hashes.items())).encode()).hexdigest()


@dataclass
class SweepResult:
    recipe: str
    sweep: SweepDecl
    points: list[PointResult]
    common_seconds: float | None
    common_instances: int
    wall_seconds: float
    executor: str = "in-process"
    metric_names: list[str] = field(default_factory=list)
    higher_better: set[str] = field(default_factory=set)  # metrics declared :higher

    def front(self, metric: str) -> list[bool]:
        sign = -1.0 if metric in self.higher_better else 1.0
        values = [p.metrics.get(metric) for p in self.points]
        return pareto_front([p.seconds for p in self.points], [None if v is None else sign * v for v in values])

    def label(self, metric: str) -> str:
        return f"{metric} (higher is better)" if metric in self.higher_better else metric


def pareto_front(costs, errors) -> list[bool]:
    """True for the points no other point beats on both cost and error (lower is better; None/NaN: never)."""

    def number(x):
        return x is not None and not (isinstance(x, float) and math.isnan(x))

    out = []
    for i, (c, e) in enumerate(zip(costs, errors)):
        if not (number(c) and number(e)):
            out.append(False)
            continue
        dominated = any(
            number(c2) and number(e2) and c2 <= c and e2 <= e and (c2 < c or e2 < e)
            for j, (c2, e2) in enumerate(zip(costs, errors))
            if j != i
        )
        out.append(not dominated)
    return out


def setting_of(recipe: Recipe, target: str) -> Any:
    """The recipe's own value of a grid target (``seed``, ``node.param``, ``node.variants``, ``node.seed``)."""
    if target == "seed":
        return recipe.seed
    node_id, _, key = target.partition(".")
    entry = recipe.nodes[node_id]
    if key in ("variants", "seed"):
        return getattr(entry, key)
    return entry.params.get(key)


def _same(a, b) -> bool:
    try:
        return bool(np.all(np.asarray(a) == np.asarray(b))) and np.shape(a) == np.shape(b)
    except (TypeError, ValueError):
        return a == b


def metric_values(ref: MetricRef, value) -> dict[str, float]:
    """The number(s) a metric reads from a Table (or a family's list of Tables: their mean)."""
    tables = value if isinstance(value, list) else [value]
    if not all(isinstance(t, Table) for t in tables):
        raise NodegraphError(f"metric {ref.name}: {ref.node}.{ref.port} is not a Table")
    columns = [ref.column] if ref.column else list(tables[0].columns)
    out = {}
    for column in columns:
        numbers = []
        for table in tables:
            if column not in table.columns:
                raise NodegraphError(
                    f"metric {ref.name}: {ref.node}.{ref.port} has no column '{column}'; "
                    f"columns: {', '.join(table.columns) or '(none)'}"
                )
            data = np.asarray(table.columns[column])
            if data.dtype.kind not in "biuf" or data.size == 0:
                if ref.column:
                    raise NodegraphError(f"metric {ref.name}: column '{column}' holds no numbers")
                break
            data = data.astype(float).ravel()
            numbers.append(
                {
                    "last": data[-1],
                    "first": data[0],
                    "min": data.min(),
                    "max": data.max(),
                    "mean": data.mean(),
                    "sum": data.sum(),
                }[ref.aggregate]
            )
        else:
            name = MetricRef(ref.node, ref.port, column, ref.aggregate).name
            out[name] = float(np.mean(numbers))
    return out


def image_pixels(value) -> np.ndarray | None:
    """An Image output's pixels; a variant family's images side by side (None: not images, or unequal)."""
    if isinstance(value, Image):
        return np.asarray(value.pixels)
    if isinstance(value, list) and value and all(isinstance(v, Image) for v in value):
        tiles = [np.asarray(v.pixels) for v in value]
        if len({t.shape for t in tiles}) == 1:
            return np.concatenate(tiles, axis=1)
    return None


def output_hash(value) -> str:
    """sha256 of the stored bytes of a value (of the hashes in order, for a family's list)."""
    if isinstance(value, list):
        return hashlib.sha256("".join(output_hash(v) for v in value).encode()).hexdigest()
    return hashlib.sha256(codec.encode(value)).hexdigest()


def grid_name(grids) -> str:
    """The name of a sweep given by ``--grid`` texts, and of its files: ``grid_`` and the grid
    (``grid_rice_sim.frames=5,10,20``, as a settings folder is named: ``output_folder.settings_folder``), so that a
    sweep over another grid never replaces the files of the first; the same grid again replaces its own."""
    from .output_folder import SETTINGS_PREFIX, settings_folder

    return "grid_" + settings_folder(Path("."), list(grids)).name.removeprefix(SETTINGS_PREFIX)


def constant_metrics(result) -> list[str]:
    """The metrics that read the same at every point of a sweep of two or more points: they cannot tell the points
    apart (an overlap measured after the contact dents is 0 whatever the settings)."""
    names = list(getattr(result, "metric_names", []) or [])
    if len(result.points) < 2:
        return []
    return [n for n in names if len({p.metrics.get(n) for p in result.points}) == 1]


def sweep_from_args(recipe: Recipe, name: str | None, grids, metrics, outputs) -> SweepDecl:
    """The sweep to run: ``--grid``/``--metric`` given on the command line, else the recipe's own
    (the one named by ``--sweep``, or its only one)."""
    from .sweep_decl import metric_problem, parse_grid, parse_metric

    issues = []
    refs = []
    for i, text in enumerate(metrics, 1):
        problem = metric_problem(text, recipe.nodes)
        if problem is not None:
            issues.append(Issue(Location("--metric", i), problem[0], given=text, suggestion=problem[1]))
        else:
            refs.append(parse_metric(text))
    if grids:
        axes = []
        for i, text in enumerate(grids, 1):
            try:
                axes.append(parse_grid(text))
            except ValueError as exc:
                issues.append(Issue(Location("--grid", i), f"cannot read '{text}': {exc}"))
        if issues:
            raise RecipeError(issues)
        grid = tuple((t, tuple(v)) for t, v in axes)
        return SweepDecl(name or grid_name(grids), grid, (), tuple(refs), tuple(outputs))
    if not recipe.sweeps:
        raise NodegraphError(
            f"{recipe.path} declares no sweeps: give --grid node.param=v1,v2,... (or add a sweeps: block)"
        )
    if name is None:
        if len(recipe.sweeps) > 1:
            names = ", ".join(recipe.sweeps)
            raise NodegraphError(f"{recipe.path} declares several sweeps; pick one with --sweep: {names}")
        name = next(iter(recipe.sweeps))
    if name not in recipe.sweeps:
        raise NodegraphError(f"--sweep {name}: {recipe.path} declares {', '.join(recipe.sweeps)}")
    decl = recipe.sweeps[name]
    if issues:
        raise RecipeError(issues)
    if metrics or outputs:
        extra = tuple(refs)
        decl = SweepDecl(
            decl.name, decl.grid, decl.fixed, decl.metrics + extra, decl.outputs + tuple(outputs), decl.doc
        )
    return decl


def _point_recipes(path, registry, decl: SweepDecl, overrides) -> list[tuple[dict, tuple[str, ...], Recipe]]:
    """Every point's recipe, all validated before anything runs (an invalid value names its point)."""
    points, issues = [], []
    base = [*decl.fixed, *overrides]  # the command line's --set wins over the sweep's own set:
    for i, values in enumerate(decl.points(), 1):
        texts = tuple(override_text(t, v) for t, v in values.items())
        try:
            points.append((values, texts, load_recipe(path, registry, [*base, *texts])))
        except RecipeError as exc:
            label = " ".join(texts)
            for issue in exc.issues:
                if issue.location.file == "--set" and (issue.location.line or 0) > len(base):
                    issue = Issue(Location(f"sweep point {i} ({label})"), issue.message, issue.node, issue.param,
                                  issue.given, issue.allowed, issue.suggestion)  # fmt: skip
                if issue not in issues:
                    issues.append(issue)
    if issues:
        raise RecipeError(issues)
    return points


def run_sweep(
    path: str | Path,
    registry,
    decl: SweepDecl,
    *,
    overrides=(),
    cache: Cache | None = None,
    pool=None,
    plugins=(),
    reporter: Reporter | None = None,
    max_seconds: float | None = None,
    rrd: Path | None = None,
) -> SweepResult:
    """Run every point of ``decl`` on the recipe at ``path`` (see the module docstring). With ``rrd``, each
    point is logged as its own recording (id from recipe and overrides: ``executor.recording_id``), all
    in that one file, so two settings can be scrubbed side by side in a viewer."""
    reporter = reporter or Reporter(quiet=True)
    started = time.perf_counter()
    base = load_recipe(path, registry, [*decl.fixed, *overrides])
    points = _point_recipes(path, registry, decl, overrides)
    refs = [f"{m.node}.{m.port}" for m in decl.metrics] + list(decl.outputs)
    wires = resolve_outputs(base, list(dict.fromkeys(refs))) if refs else list(base.outputs)
    wires = list(dict.fromkeys(wires))

    plans: list[dict[Instance, str]] = []
    for _, _, recipe in points:
        plan = Plan(recipe)
        plan.add({w.node for w in wires})
        plans.append(dict(plan.keys))
    common = set.intersection(*(set(p.values()) for p in plans)) if len(plans) > 1 else set()

    times: dict[str, float] = {}  # instances computed during this sweep: key → seconds
    if pool is not None:  # every point's missing instances as one task graph; shared ones are one job
        if cache is None:
            raise NodegraphError("workers hand results over through the cache: a pool needs it (no --no-cache)")
        jobs = {}
        for _, _, recipe in points:
            for job in plan_jobs(recipe, wires, cache, RecipeRef.of(recipe, plugins), max_seconds):
                jobs.setdefault(job.key, job)
        if jobs:
            for key, result in pool.compute(list(jobs.values()), cache.directory, reporter).items():
                if result.record.status != "cached":
                    times[key] = result.record.seconds
    results = []
    higher: set[str] = set()
    task = reporter.task(f"sweep {decl.name}: {len(points)} points", len(points))
    with tempfile.TemporaryDirectory(prefix="nodegraph-sweep-") as scratch, task as tick:
        parts = None if rrd is None else Path(scratch)  # each point's recording, merged into rrd at the end
        for (values, texts, recipe), keys in zip(points, plans):
            cached_before = {k for k in keys.values() if cache is not None and cache.has(k) and k not in times}
            run = run_recipe(
                recipe,
                outputs=[str(w) for w in wires],
                cache=cache,
                rrd=None if parts is None else parts / f"{len(results):04d}.rrd",
                reporter=Reporter(quiet=True),
                max_seconds=max_seconds,
            )
            label_key = {inst.label: key for inst, key in keys.items()}
            for record in run.records:
                key = label_key.get(record.node)
                if key is not None and record.status not in ("cached", "failed") and key not in times:
                    times[key] = record.seconds
            own = {k for k in keys.values() if k not in common}
            seconds = _seconds(own, times, cache)
            metrics = {}
            for ref in decl.metrics:
                values_of_ref = metric_values(ref, run.output(f"{ref.node}.{ref.port}"))
                metrics.update(values_of_ref)
                higher |= set(values_of_ref) if ref.higher else set()
            outputs = {str(w): run.output(str(w)) for w in wires}
            results.append(
                PointResult(
                    values=values,
                    overrides=texts,
                    seconds=seconds,
                    ran=len(own - cached_before),
                    cached=len(own & cached_before),
                    metrics=metrics,
                    hashes={name: output_hash(value) for name, value in outputs.items()},
                    recipe_setting=all(_same(v, setting_of(base, t)) for t, v in values.items()),
                    images={name: px for name, value in outputs.items() if (px := image_pixels(value)) is not None},
                )
            )
            tick()
            reporter.info(f"point {len(results)}/{len(points)} {' '.join(texts)}: {describe_point(results[-1])}")
        if parts is not None:
            merge_recordings(sorted(parts.glob("*.rrd")), rrd)
    names = list(dict.fromkeys(n for p in results for n in p.metrics))
    return SweepResult(
        recipe=base.name,
        sweep=decl,
        points=results,
        common_seconds=_seconds(common, times, cache),
        common_instances=len(common),
        wall_seconds=time.perf_counter() - started,
        executor=getattr(pool, "description", "in-process") if pool is not None else "in-process",
        metric_names=names,
        higher_better=higher,
    )


def _seconds(keys, times, cache) -> float | None:
    total = 0.0
    for key in keys:
        seconds = times.get(key)
        if seconds is None and cache is not None:
            seconds = cache.recorded_seconds(key)
        if seconds is None:
            return None
        total += seconds
    return total


def describe_point(point: PointResult) -> str:
    cost = "time unknown" if point.seconds is None else f"{point.seconds:.3f} s"
    shown = ", ".join(f"{k} {_fmt(v)}" for k, v in list(point.metrics.items())[:3])
    return f"{cost} ({point.ran} ran, {point.cached} cached)" + (f"; {shown}" if shown else "")


def _fmt(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


# writing ----------------------------------------------------------------------------------------
def sweep_table(result: SweepResult) -> tuple[list[str], list[list[str]]]:
    """Header and rows shared by the Markdown and the CSV table."""
    axes = [t for t, _ in result.sweep.grid]
    names = result.metric_names
    fronts = {m: result.front(m) for m in names}
    shown = [f"{m} ↑" if m in result.higher_better else m for m in names]
    header = ["point", *axes, "seconds", "ran", "cached", *shown, "pareto", "outputs sha256", "recipe setting"]
    rows = []
    for i, p in enumerate(result.points):
        on = [m for m in names if fronts[m][i]]
        rows.append(
            [
                str(i + 1),
                *(_fmt(p.values[a]) for a in axes),
                "" if p.seconds is None else f"{p.seconds:.4f}",
                str(p.ran),
                str(p.cached),
                *(_fmt(p.metrics.get(m)) for m in names),
                " ".join(on),
                p.digest[:16],
                "yes" if p.recipe_setting else "",
            ]
        )
    return header, rows


def sweep_markdown(result: SweepResult, image: str | None = None, sheets: tuple[str, ...] = ()) -> str:
    header, rows = sweep_table(result)
    decl = result.sweep
    common = f"{result.common_instances} node instances common to every point" + (
        "" if result.common_seconds is None else f" ({result.common_seconds:.3f} s, counted once)"
    )
    lines = [
        f"## Sweep `{decl.name}` of `{result.recipe}`",
        "",
        *([decl.doc, ""] if decl.doc else []),
        f"{len(result.points)} points on {result.executor}, {result.wall_seconds:.1f} s in all; {common}. "
        "*seconds*: wall time of the point's own node instances; *ran*: of those, computed during this sweep "
        "(for this point or an earlier one that shares them); *cached*: found in the cache before; "
        "*pareto*: the metrics on whose time–metric Pareto front the point lies (lower time is better, and a lower "
        "metric, except one marked ↑: higher is better); "
        "*outputs sha256*: of the pulled outputs' stored bytes; *recipe setting*: the recipe's own values"
        + (f"; fixed: `{' '.join(decl.fixed)}`" if decl.fixed else "")
        + ".",
        "",
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
    ]
    for row in rows:
        cells = [c if c else "" for c in row]
        if row[-1] == "yes":
            cells = [f"**{c}**" if c else c for c in cells]
        lines.append("| " + " | ".join(cells) + " |")
    if image:
        lines += ["", f"![{decl.name}]({image})"]
    for sheet in sheets:
        lines += ["", f"![{sheet}]({sheet})"]
    return "\n".join(lines) + "\n"


def sweep_csv(result: SweepResult) -> str:
    header, rows = sweep_table(result)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    return buffer.getvalue()


def plot_sweep(result: SweepResult, path: Path) -> Path | None:
    """One panel per metric (at most four): time against the metric, the Pareto front and the recipe's
    setting marked. Needs matplotlib; returns None (and draws nothing) without it or without metrics."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    names = result.metric_names[:4]
    if not names:
        return None
    fig, axes = plt.subplots(1, len(names), figsize=(6 * len(names), 4.6), squeeze=False)
    for ax, name in zip(axes[0], names):
        pts = [(p.seconds, p.metrics.get(name), p) for p in result.points]
        pts = [(x, y, p) for x, y, p in pts if x is not None and y is not None and math.isfinite(y)]
        if not pts:
            continue
        front = result.front(name)
        ax.scatter([x for x, _, _ in pts], [y for _, y, _ in pts], s=22, color="C0", zorder=2)
        on = sorted((p.seconds, p.metrics[name]) for p, f in zip(result.points, front) if f)
        if on:
            ax.plot(*zip(*on), "-o", color="C3", mfc="none", ms=9, label="Pareto front", zorder=3)
        for x, y, p in pts:
            text = ",".join(_fmt(v) for v in p.values.values())
            ax.annotate(
                text + (" (recipe)" if p.recipe_setting else ""),
                (x, y),
                fontsize=7,
                xytext=(3, 3),
                textcoords="offset points",
                color="C3" if p.recipe_setting else "0.25",
            )
            if p.recipe_setting:
                ax.scatter([x], [y], s=90, marker="*", color="C3", zorder=4, label="recipe setting")
        xs = [x for x, _, _ in pts]
        ys = [y for _, y, _ in pts]
        if min(xs) > 0 and max(xs) / min(xs) > 8:
            ax.set_xscale("log")
        if min(ys) > 0 and max(ys) / min(ys) > 8:
            ax.set_yscale("log")
        ax.set_xlabel("wall time of the point's own nodes (s)")
        ax.set_ylabel(result.label(name))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes_names = " × ".join(t for t, _ in result.sweep.grid)
    fig.suptitle(f"{result.recipe}: sweep {result.sweep.name} ({axes_names}); labels: {axes_names}", fontsize=10)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    atomic_write(path, buffer.getvalue())
    return path


def contact_sheets(result: SweepResult, directory: Path) -> list[Path]:
    """``<sweep>_<output>.png`` for each pulled Image output (e.g. ``preview.image``): the points' images side
    by side, a row per value of the first axes and a column per value of the last, each labelled with its
    point's parameter values (and its recipe-setting mark)."""
    names = list(dict.fromkeys(n for p in result.points for n in p.images))
    columns = len(result.sweep.grid[-1][1]) if result.sweep.grid else len(result.points)
    written = []
    for name in names:
        tiles = [p.images.get(name) for p in result.points]
        if any(t is None for t in tiles) or len({t.shape[:2] for t in tiles}) != 1:
            continue  # a point without it, or tiles of different sizes: no sheet rather than a misleading one
        labels = [" ".join(p.overrides) + (" (recipe)" if p.recipe_setting else "") for p in result.points]
        height = max(20, min(40, tiles[0].shape[0] // 8))
        pixels = grid_pixels([np.asarray(t) for t in tiles], max(1, columns), labels, gap=8, label_height=height)
        path = directory / f"{result.sweep.name}_{name.replace('.', '_')}.png"
        atomic_write(path, _png(pixels))
        written.append(path)
    return written


def _png(pixels: np.ndarray) -> bytes:
    from PIL import Image as PILImage

    buffer = io.BytesIO()
    PILImage.fromarray(pixels).save(buffer, format="PNG")
    return buffer.getvalue()


def _has_matplotlib() -> bool:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    return True


NO_MATPLOTLIB = "no plot: matplotlib is not installed (pip install matplotlib draws it on the next sweep)"


def write_sweep(result: SweepResult, directory: Path, warn=None) -> list[Path]:
    """``<directory>/<sweep>.md``, ``.csv`` and ``.png`` (the plot only with matplotlib and metrics), and a
    contact sheet per pulled Image output. Without matplotlib the plot is missing and said so (``warn``, and a line
    in the .md), never silently; a metric that reads the same at every point is said too (``constant_metrics``)."""
    directory.mkdir(parents=True, exist_ok=True)
    stem = result.sweep.name
    image = plot_sweep(result, directory / f"{stem}.png")
    sheets = contact_sheets(result, directory)
    markdown = sweep_markdown(result, image.name if image else None, tuple(p.name for p in sheets))
    if image is None and result.metric_names and not _has_matplotlib():
        markdown += f"\n({NO_MATPLOTLIB})\n"
        if warn is not None:
            warn(f"{NO_MATPLOTLIB}; the table is in {directory / f'{stem}.md'}")
    for name in constant_metrics(result):  # said, in the table and on the terminal: it cannot tell points apart
        line = f"{name} is {_fmt(result.points[0].metrics[name])} at every point: it does not vary with this grid"
        markdown += f"\n({line})\n"
        if warn is not None:
            warn(f"{line}; pick a metric that does (the columns of a Table output: `nodegraph describe TYPE`)")
    atomic_write(directory / f"{stem}.md", markdown.encode())
    atomic_write(directory / f"{stem}.csv", sweep_csv(result).encode())
    return [directory / f"{stem}.md", directory / f"{stem}.csv"] + ([image] if image else []) + sheets


__all__ = [
    "PointResult",
    "SweepResult",
    "metric_values",
    "pareto_front",
    "run_sweep",
    "sweep_from_args",
    "write_sweep",
]
