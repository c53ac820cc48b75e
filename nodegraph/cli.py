"""The ``nodegraph`` command: run, watch, sweep, check, nodes, describe, graph, clean, cache, docs, inspect.

Exit status: 0 success, 1 a node failed, 2 the recipe or the command line is invalid, 130 interrupted.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import signal
import sys
import threading
import time
from pathlib import Path

from rich.console import Console

from . import interrupt, runtime
from .cache import (
    LIMIT_ENV_VAR,
    LIMIT_FILE,
    Cache,
    check_writable,
    default_cache_dir,
    format_size,
    parse_size,
)
from .compile_ahead import kernels_due
from .describe import describe_command
from .errors import NodeFailure, NodegraphError, RecipeError
from .executor import resolve_outputs, run_recipe
from .output_folder import recipe_folder, settings_folder
from .recipe import Recipe, load_recipe
from .registry import default_registry
from .report import Reporter
from .rerun_log import has_display
from .watch import Superseded, WatchSession, run_name

SETTLE_S = 0.05  # watch: how long a recipe file's bytes must stay the same before a run starts
SWEEP_RRD = Path("<sweep>.rrd")  # --rrd given without a path
RRD_MAGIC = b"RRF2"  # the first bytes of a Rerun recording
FILE_KINDS = {
    b"\x89PNG": "a PNG image",
    b"glTF": "a glTF binary (.glb)",
    b"PXR-": "a USD crate file",
    b"ply": "a PLY mesh",
}


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--plugin",
        action="append",
        default=[],
        metavar="PATH.py",
        help="load node types from a Python file (repeatable)",
    )
    parser.add_argument(
        "--cache-dir",
        type=Path,
        default=None,
        help="cache directory (default: $NODEGRAPH_CACHE, else ~/.cache/nodegraph/cache)",
    )


def _draft(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--draft",
        action="store_true",
        help="apply the recipe's draft: block (reduced counts and a small preview: seconds, to iterate on a look); "
        "--set still wins",
    )


def _distributed(parser: argparse.ArgumentParser) -> None:
    group = parser.add_mutually_exclusive_group()
    group.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="compute node instances on this Dask scheduler's workers (they share the cache by path)",
    )
    group.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="start a Dask LocalCluster of N worker processes here for the node instances",
    )


class _Parser(argparse.ArgumentParser):
    """An argument the command does not know is refused by that command (``nodegraph run``'s usage, not the top
    level's), with the nearest of its options (``--drfat``: did you mean --draft?)."""

    commands: dict[str, argparse.ArgumentParser] = {}  # the top level's: each command's parser, by name

    def parse_args(self, args=None, namespace=None):
        parsed, extra = self.parse_known_args(args, namespace)
        if extra:
            owner = self.commands.get(getattr(parsed, "command", None), self)
            owner.error(unknown_arguments(extra, owner, getattr(parsed, "overrides", None) or []))
        return parsed


def unknown_arguments(extra: list[str], parser: argparse.ArgumentParser, overrides: list[str] = ()) -> str:
    """What argparse says of arguments it did not take, and for each misspelt option the nearest of ``parser``'s;
    a value left after a ``--set`` without ``=`` (``--set rice_sim.frames 3``) is shown joined."""
    import difflib

    options = sorted(set(re.findall(r"--[a-z][a-z-]*", parser.format_usage())))
    hints = []
    bare = [text for text in overrides if "=" not in text]
    for text, arg in zip(bare, [a for a in extra if not a.startswith("-")]):
        hints.append(f"{arg}: did you mean --set {text}={arg}?")
    for arg in extra:
        if arg.startswith("-"):
            near = difflib.get_close_matches(arg.partition("=")[0], options, n=1, cutoff=0.6)
            if near:
                hints.append(f"{arg}: did you mean {near[0]}?")
    return f"unrecognized arguments: {' '.join(extra)}" + "".join(f"; {hint}" for hint in hints)


YES_HELP = "run however long the nodes expect to take, however much memory they expect to hold"


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="nodegraph", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    parser.commands = sub.choices

    run = sub.add_parser("run", help="run a recipe and write its outputs")
    run.add_argument("recipe", type=Path)
    run.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="NODE.PARAM=VALUE",
        help="override a parameter (repeatable); also seed=N, NODE.variants=N, NODE.seed=N",
    )
    run.add_argument(
        "--output",
        dest="outputs",
        action="append",
        default=[],
        metavar="NODE[.PORT]",
        help="compute only this output and what it needs (repeatable)",
    )
    run.add_argument("--no-cache", action="store_true", help="neither read nor write the cache")
    run.add_argument(
        "--rrd", type=Path, default=None, help="Rerun recording path (default outputs/<recipe>/<recipe>.rrd)"
    )
    run.add_argument("--no-rrd", action="store_true", help="do not record to Rerun")
    run.add_argument("--spawn", action="store_true", help="also stream to a Rerun viewer")
    run.add_argument(
        "--out-dir",
        type=Path,
        default=None,
        help="where outputs go (default outputs/<recipe>, --draft: <recipe>_draft)",
    )
    _draft(run)
    run.add_argument(
        "-q", "--quiet", action="store_true", help="print nothing but errors and the earlier outputs a run removes"
    )
    run.add_argument(
        "--max-minutes",
        type=float,
        default=10.0,
        metavar="M",
        help="a node whose own estimate is longer than this refuses to start (default 10)",
    )
    run.add_argument("--yes", action="store_true", help=YES_HELP)
    _distributed(run)
    _common(run)

    watch = sub.add_parser(
        "watch", help="run a recipe, then again on every save of its file (only what the edit changed recomputes)"
    )
    watch.add_argument("recipe", type=Path)
    watch.add_argument("--set", dest="overrides", action="append", default=[], metavar="NODE.PARAM=VALUE")
    watch.add_argument("--output", dest="outputs", action="append", default=[], metavar="NODE[.PORT]")
    watch.add_argument("--spawn", action="store_true", help="stream every run to a Rerun viewer (one, kept open)")
    watch.add_argument("--no-rrd", action="store_true", help="do not record to Rerun")
    watch.add_argument("--out-dir", type=Path, default=None, help="where outputs go (as for run)")
    watch.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors and what each run wrote")
    watch.add_argument("--poll", type=float, default=0.1, metavar="S", help="seconds between looks at the file")
    watch.add_argument("--runs", type=int, default=None, metavar="N", help="stop after N runs (scripts, tests)")
    watch.add_argument("--max-minutes", type=float, default=10.0, metavar="M", help="as for run (default 10)")
    watch.add_argument("--yes", action="store_true", help=YES_HELP)
    _draft(watch)
    _common(watch)

    sweep = sub.add_parser("sweep", help="run a recipe at every point of a parameter grid: cost against metrics")
    sweep.add_argument("recipe", type=Path)
    sweep.add_argument(
        "--grid",
        dest="grids",
        action="append",
        default=[],
        metavar="NODE.PARAM=V1,V2,...",
        help="one axis of the grid (repeatable; every combination runs); default: the recipe's sweeps: block",
    )
    sweep.add_argument(
        "--metric",
        dest="metrics",
        action="append",
        default=[],
        metavar="NODE.PORT[.COLUMN][:AGG][:higher]",
        help="a number read from a Table output per point (AGG: last, first, min, max, mean, sum; default last); "
        ":higher marks a metric better higher on the Pareto front (else lower is better, an error)",
    )
    sweep.add_argument("--sweep", dest="sweep_name", default=None, help="which of the recipe's sweeps to run")
    sweep.add_argument("--set", dest="overrides", action="append", default=[], metavar="NODE.PARAM=VALUE")
    _draft(sweep)
    sweep.add_argument(
        "--output", dest="outputs", action="append", default=[], metavar="NODE[.PORT]", help="also pull this output"
    )
    sweep.add_argument(
        "--out-dir",
        type=Path,
        default=None,
        help="where the table and plot go (default outputs/<recipe>/sweeps, --draft: outputs/<recipe>_draft/sweeps)",
    )
    sweep.add_argument(
        "--rrd",
        type=Path,
        nargs="?",
        const=SWEEP_RRD,
        default=None,
        metavar="PATH",
        help="log each point as its own recording, all in this one .rrd (default path: <out-dir>/<sweep>.rrd)",
    )
    sweep.add_argument("--no-cache", action="store_true", help="neither read nor write the cache (every point cold)")
    sweep.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors and the written files")
    sweep.add_argument("--max-minutes", type=float, default=10.0, metavar="M", help="as for run (default 10)")
    sweep.add_argument("--yes", action="store_true", help=YES_HELP)
    _distributed(sweep)
    _common(sweep)

    check = sub.add_parser("check", help="validate a recipe and estimate its cost; nothing runs")
    check.add_argument("recipe", type=Path)
    check.add_argument("--set", dest="overrides", action="append", default=[], metavar="NODE.PARAM=VALUE")
    check.add_argument("--yes", action="store_true", help="pass a request larger than a run starts on unasked")
    check.add_argument(
        "--max-minutes",
        type=float,
        default=10.0,
        metavar="M",
        help="as for run: a node estimated to take longer is refused (default 10)",
    )
    _draft(check)
    _common(check)

    nodes = sub.add_parser("nodes", help="list every node type")
    _common(nodes)

    describe = sub.add_parser(
        "describe",
        help="ports and parameters of a node type; a step's name in a recipe here or in graphs/, or the start of a "
        "type's name, finds its type; a step's values in its recipe are shown beside the defaults",
        usage="nodegraph describe [RECIPE.yaml] TYPE_OR_STEP[.SETTING]",
        description="A node type's ports and parameters. A step's name (egg_base) is looked up in RECIPE.yaml, else "
        "in the recipes here and in graphs/, and the values its recipe sets (and its draft: block) are shown beside "
        "the type's defaults.",
    )
    describe.add_argument("first", metavar="RECIPE.yaml", help="the recipe whose step to describe (optional)")
    describe.add_argument("second", nargs="?", metavar="TYPE_OR_STEP[.SETTING]")
    _common(describe)

    docs = sub.add_parser("docs", help="Markdown reference of every node type, generated from the declarations")
    docs.add_argument("--out", type=Path, default=None, help="write to this file instead of stdout")
    _common(docs)

    graph = sub.add_parser("graph", help="print a recipe's graph")
    graph.add_argument("recipe", type=Path)
    graph.add_argument("--dot", action="store_true", help="Graphviz DOT instead of text")
    graph.add_argument("--set", dest="overrides", action="append", default=[], metavar="NODE.PARAM=VALUE")
    _draft(graph)
    _common(graph)

    inspect = sub.add_parser("inspect", help="what a .rrd holds: recordings, entity tree, timelines, blueprint views")
    inspect.add_argument("rrd", type=Path)
    inspect.add_argument(
        "--depth", type=int, default=6, metavar="N", help="entity tree levels shown (default 6; deeper ones counted)"
    )
    _common(inspect)

    clean = sub.add_parser(
        "clean",
        help="remove the outputs of a recipe's earlier runs and partial recordings",
        description="lists, then removes, what earlier runs left in a recipe's output folders: files a later run of "
        "the same settings did not write again, every --set folder but the latest run's, and the partial recordings "
        "of stopped or failed runs. The recipe's own folder and its draft's keep their last run's files. Only files "
        "a run's manifest lists, as that run wrote them",
    )
    clean.add_argument("recipe", type=Path)
    clean.add_argument("--dry-run", action="store_true", help="list what would go; remove nothing")
    clean.add_argument("--yes", "-y", action="store_true", help="remove without asking (at a terminal it asks)")
    _common(clean)

    cache = sub.add_parser(
        "cache",
        help="inspect, clear or limit the cache",
        description="info: size and limit; clear: remove everything; limit SIZE: keep at most SIZE (e.g. 2GiB), "
        "removing the least recently used results when a run ends above it ($NODEGRAPH_CACHE_LIMIT overrides)",
    )
    cache.add_argument("action", choices=["info", "clear", "limit"])
    cache.add_argument("size", nargs="?", help="limit: the new size limit (e.g. 500MiB, 2GiB)")
    cache.add_argument("--yes", action="store_true", help="clear without asking (asked only on a terminal)")
    _common(cache)
    return parser


def _cmd_run(args, registry, session: WatchSession | None = None) -> int:
    if args.no_rrd and (args.spawn or args.rrd):
        given = " and ".join(f for f, on in (("--spawn", args.spawn), ("--rrd", args.rrd)) if on)
        raise NodegraphError(
            f"--no-rrd contradicts {given}: a viewer and a recording file both need the recording; drop one of them"
        )
    recipe = load_recipe(args.recipe, registry, args.overrides, draft=args.draft)
    weighed = None
    if _work_due(recipe, args.outputs, None if args.no_cache else (args.cache_dir or default_cache_dir())):
        # what takes a moment to check (a placement against its shape's mesh) and the cost estimate, before any work
        asked = tuple(w.node for w in resolve_outputs(recipe, args.outputs)) if args.outputs else None
        weighed = load_recipe(
            args.recipe,
            registry,
            args.overrides,
            draft=args.draft,
            work=True,
            yes=args.yes,
            limits=_limits(args, asked),
        )
    out_dir = args.out_dir or settings_folder(recipe_folder(args.recipe, recipe.name, args.draft), args.overrides)
    rrd = None if args.no_rrd else (args.rrd or out_dir / f"{recipe.file_name}.rrd")
    cache = None if args.no_cache else Cache(args.cache_dir or default_cache_dir())
    # every place the run writes, checked before anything is computed
    made = check_writable(out_dir, "outputs", "choose another folder with --out-dir")
    if rrd is not None:
        made += check_writable(rrd.parent, "Rerun recording", "choose another path with --rrd, or --no-rrd")
    if cache is not None:
        check_writable(cache.directory, "cache", "choose another with --cache-dir (or $NODEGRAPH_CACHE), or --no-cache")
    reporter = Reporter(console=Console(stderr=True, highlight=False), quiet=args.quiet)
    reporter.fold = session is None  # a watch's log lists every step of each run: what the save re-ran
    reporter.info(f"outputs go to {out_dir}{os.sep}")
    if weighed is not None:
        weighed.cost.compiles = kernels_due(weighed)
        reporter.info("estimate: " + "; ".join(weighed.cost.lines()))
    spawn = args.spawn
    if spawn and not has_display():  # said before anything is computed
        reporter.warn(
            f"--spawn: no display (DISPLAY and WAYLAND_DISPLAY are unset), so no viewer opens; the "
            f"recording is written to {rrd} (open it later with: rerun {rrd})"
        )
        spawn = False
    started = time.time() - 1.0  # file times may be rounded down to the second
    stopped = False
    try:
        with _pool(args, cache, reporter) as pool:
            result = run_recipe(
                recipe,
                outputs=args.outputs or None,
                cache=cache,
                out_dir=out_dir,
                rrd=rrd,
                spawn=spawn,
                reporter=reporter,
                max_seconds=None if args.yes else 60 * args.max_minutes,
                pool=pool,
                plugins=args.plugin,
                session=session,
                estimate=None if weighed is None else weighed.cost,
            )
        if session is not None:
            session.keep(result)
        if cache is not None:  # its entries go last when the cache is trimmed, until the recipe runs again
            kind = " --draft" if args.draft else ""
            cache.keep_run(
                f"{Path(args.recipe).resolve()}{kind}{' --set' if args.overrides else ''}", result.keys.values()
            )
        reporter.print_summary()  # before the cache's trim: what it removed is said below the table
    except KeyboardInterrupt:
        stopped = True
        reporter.print_summary()
        _remove_empty(made)  # stopped before any output was written: no empty folder is left
        raise
    except NodeFailure:
        reporter.print_summary()
        raise
    finally:
        if not stopped:  # a stop ends at once (``interrupt.GRACE``): the next run trims the cache
            _trim(cache, started, reporter)
    if not args.quiet:
        done = "up to date:" if result.current else "wrote"  # current: the last run's files, nothing written
        for path in result.files:
            print(f"{done} {path}")
        if result.rrd is not None:
            print(f"{done} {result.rrd} (open with: rerun {result.rrd})")
        if args.out_dir is None and session is None and (line := _prune_line(args.recipe, recipe.name)):
            print(line)
        print(_outputs_line(out_dir, chosen=args.out_dir is not None))
    return 0


def _outputs_line(out_dir: Path, chosen: bool) -> str:
    """A run's last line: the folder its outputs are in, as a whole path (the recipe's project's ``outputs/``,
    wherever the command ran)."""
    return f"the outputs are in {out_dir.resolve()}{os.sep}" + ("" if chosen else " (--out-dir chooses another folder)")


def _remove_empty(folders: list[Path]) -> None:
    """Remove those of ``folders`` (as ``check_writable`` made them, outermost first) that are empty."""
    for folder in reversed(folders):
        with contextlib.suppress(OSError):
            folder.rmdir()


def _weighs(spec) -> bool:
    """Whether a node's run is weighed first (its ``check_work``, its ``cost``): not a node that is never stored
    (``store=False``: made again from its cached inputs in a moment, it is never in the cache, and weighing it made
    every cached re-run of a scene load trimesh for its shapes, ≈ 0.7 s)."""
    return spec.store and (spec.check_work is not None or spec.cost is not None)


def _work_due(recipe: Recipe, outputs: list[str], cache_dir: Path | None) -> bool:
    """Whether a node with a ``check_work`` or a ``cost`` would run for ``outputs`` (its result not in the cache): a
    cached re-run skips those checks, the estimate and what they load (a shape's mesh: trimesh, 0.6 CPU s)."""
    from .plan import Plan

    wires = resolve_outputs(recipe, outputs) if outputs else list(recipe.outputs)
    plan = Plan(recipe)
    order = plan.add({w.node for w in wires})
    checked = [inst for inst in order if _weighs(recipe.nodes[inst.node].spec)]
    if not checked:
        return False
    cache = Cache(cache_dir) if cache_dir is not None else None
    return cache is None or not all(cache.has(plan.keys[inst]) for inst in checked)


@contextlib.contextmanager
def _pool(args, cache, reporter):
    """The Dask pool that --scheduler or --workers asks for (None: in-process), closed afterwards."""
    if args.scheduler is None and args.workers is None:
        yield None
        return
    if cache is None:
        raise NodegraphError("--scheduler/--workers: workers hand results over through the cache; drop --no-cache")
    from .dask_pool import DaskPool

    pool = DaskPool(address=args.scheduler, workers=args.workers, warn=reporter.warn)
    try:
        reporter.info(f"node instances go to {pool.description}")
        yield pool
    finally:
        pool.close()


def _cmd_watch(args, registry) -> int:
    """Run, then run again whenever the recipe file's bytes change. The cache makes a re-run compute only the
    nodes an edit changed; a bad edit prints its error (file:line, node, parameter) and the last good outputs
    and recording stay as they were until the next save. A save during a run stops what it no longer needs
    (``WatchSession``) and runs the new version."""
    import hashlib

    from .plan import Plan

    args.no_cache, args.rrd, args.scheduler, args.workers = False, None, None, None  # the cache is the point

    def digest():
        try:
            text = args.recipe.read_bytes()
        except OSError:
            text = b""  # an editor replacing the file
        return hashlib.sha256(text).digest() if text.strip() else None  # None: being written, look again

    def settled(last):
        """The file's digest once a save has settled, if it differs from ``last``; else None."""
        now = digest()
        if now is None or now == last:
            return None
        time.sleep(SETTLE_S)  # a save in progress: take it once the bytes have stayed the same a moment
        return now if digest() == now else None

    def needed_keys() -> set[str] | None:
        """The cache keys the file as saved now needs; None when it does not load (a bad edit)."""
        try:
            recipe = load_recipe(args.recipe, registry, args.overrides, draft=args.draft)
            wires = resolve_outputs(recipe, args.outputs) if args.outputs else list(recipe.outputs)
            plan = Plan(recipe)
            plan.add({w.node for w in wires})
        except (RecipeError, NodegraphError):
            return None
        return set(plan.keys.values())

    saved: dict[bytes, float] = {}  # when a save made during a run was seen, by the file's digest

    def supervise(run_digest, done: threading.Event) -> None:
        """During a run: tell the session about every save, so that it stops what the save made unneeded."""
        last = run_digest
        while not done.wait(args.poll):
            noticed = time.perf_counter()
            now = settled(last)
            if now is not None:
                last, saved[now] = now, noticed
                session.supersede(needed_keys())

    def warm_up(run_digest) -> None:
        """Between saves: ready the next edit (``WatchSession.warm_up``); a save stops the step under way."""
        started, steps, done = time.perf_counter(), 0, threading.Event()

        def look() -> None:
            while not done.wait(args.poll):
                noticed = time.perf_counter()
                now = settled(run_digest)
                if now is not None:
                    saved[now] = noticed  # the update's latency counts from here, not from the warm-up's end
                    session.stop_warm_up()
                    return

        session.warm_stopped = False  # before the watcher starts: a save during the warm-up's planning counts
        watcher = threading.Thread(target=look, daemon=True)
        watcher.start()
        try:
            for _ in session.warm_up(cache):
                steps += 1
        except Superseded:
            pass
        finally:
            done.set()
            watcher.join()
        if not session.warm_stopped:
            took = time.perf_counter() - started
            print(f"ready: {steps} step(s) loaded ahead in {took:.1f} s, so a save updates fast", flush=True)

    seen, runs, session = None, 0, WatchSession()
    cache = Cache(args.cache_dir or default_cache_dir())
    previous = signal.signal(signal.SIGINT, session.interrupted)
    try:
        while args.runs is None or runs < args.runs:
            noticed = time.perf_counter()
            now = settled(seen)
            if now is None:
                time.sleep(args.poll)
                continue
            seen, runs, ok = now, runs + 1, False
            noticed = saved.pop(now, noticed)
            saved.clear()
            session.begin(runs, noticed)
            done = threading.Event()
            supervisor = threading.Thread(target=supervise, args=(now, done), daemon=True)
            supervisor.start()
            try:
                _cmd_run(args, registry, session)
                print(f"{run_name(runs)} done in {time.perf_counter() - noticed:.1f} s", flush=True)
                ok = True
            except Superseded as exc:
                print(f"{run_name(runs)}: stopped at {exc}: the file was saved again", flush=True)
            except RecipeError as exc:
                print(str(exc), file=sys.stderr)
                print(f"{run_name(runs)}: not run; the last good outputs stay", flush=True)
            except (NodeFailure, NodegraphError) as exc:
                print(f"error: {exc}", file=sys.stderr)
                print(f"{run_name(runs)}: failed; the last good outputs stay", flush=True)
            finally:
                done.set()
                supervisor.join()
                session.begin(runs, noticed)  # a stop signalled as the run ended is dropped
            if args.runs is None or runs < args.runs:
                print(f"watching {args.recipe} (Ctrl-C to stop)", flush=True)
                if ok:
                    warm_up(now)
    finally:
        signal.signal(signal.SIGINT, previous)
    return 0


def _cmd_sweep(args, registry) -> int:
    from .sweep import run_sweep, sweep_from_args, write_sweep

    base = load_recipe(args.recipe, registry, args.overrides, draft=args.draft)
    decl = sweep_from_args(base, args.sweep_name, args.grids, args.metrics, args.outputs)
    out_dir = args.out_dir or recipe_folder(args.recipe, base.name, args.draft) / "sweeps"
    cache = None if args.no_cache else Cache(args.cache_dir or default_cache_dir())
    check_writable(out_dir, "sweep table", "choose another folder with --out-dir")
    if cache is not None:
        check_writable(cache.directory, "cache", "choose another with --cache-dir (or $NODEGRAPH_CACHE), or --no-cache")
    rrd = None if args.rrd is None else (out_dir / f"{decl.name}.rrd" if args.rrd == SWEEP_RRD else args.rrd)
    if rrd is not None:
        check_writable(rrd.parent, "Rerun recording", "choose another path with --rrd")
    reporter = Reporter(console=Console(stderr=True, highlight=False), quiet=args.quiet)
    reporter.info(f"sweep tables go to {out_dir}{os.sep}")
    started = time.time() - 1.0
    with _pool(args, cache, reporter) as pool:
        result = run_sweep(
            args.recipe,
            registry,
            decl,
            overrides=list(base.overrides),  # the draft's, then --set
            cache=cache,
            pool=pool,
            plugins=args.plugin,
            reporter=reporter,
            max_seconds=None if args.yes else 60 * args.max_minutes,
            rrd=rrd,
        )
    _trim(cache, started, reporter)
    for path in write_sweep(result, out_dir, warn=reporter.warn):
        print(f"wrote {path}")
    if rrd is not None:
        print(f"wrote {rrd}: {len(result.points)} recordings, one per point (open with: rerun {rrd})")
    return 0


def _cmd_inspect(args, registry) -> int:
    from .inspect_rrd import describe_rrd

    if not args.rrd.is_file():
        raise NodegraphError(f"{args.rrd}: no such file (give a .rrd written by nodegraph run or sweep)")
    with open(args.rrd, "rb") as file:
        head = file.read(4)
    if head != RRD_MAGIC:
        kind = (
            "empty"
            if not head
            else next((n for magic, n in FILE_KINDS.items() if head.startswith(magic)), "another file")
        )
        raise NodegraphError(
            f"{args.rrd} is {kind}, not a Rerun recording: inspect reads the .rrd that nodegraph run or sweep writes "
            "(outputs/<recipe>/<recipe>.rrd)"
        )
    print(describe_rrd(args.rrd, depth=args.depth))
    return 0


def _cmd_check(args, registry) -> int:
    recipe = load_recipe(
        args.recipe, registry, args.overrides, draft=args.draft, work=True, yes=args.yes, limits=_limits(args)
    )
    if recipe.draft and not args.draft:  # the draft's values are checked too, where they would apply
        load_recipe(args.recipe, registry, args.overrides, draft=True)
    instances = sum(entry.family or 1 for entry in recipe.nodes.values())
    sweeps = "".join(f", sweep {d.name} ({len(d.points())} points)" for d in recipe.sweeps.values())
    print(
        f"{args.recipe}: OK — {len(recipe.nodes)} nodes ({instances} instances), "
        f"outputs {', '.join(map(str, recipe.outputs))}, effects: {', '.join(sorted(recipe.effects)) or 'none'}"
        + sweeps
        + (f", draft: {len(recipe.draft)} settings" if recipe.draft else "")
    )
    for warning in recipe.warnings:  # what a run will warn of (a user's mesh file it repairs)
        print(f"  warning: {warning}")
    recipe.cost.compiles = kernels_due(recipe)
    for line in recipe.cost.lines():
        print(f"  estimate: {line}")
    for decl in recipe.sweeps.values():
        print(f"  estimate: {_sweep_time(args, registry, decl)}")
    return 0


def _sweep_time(args, registry, decl) -> str:
    """A sweep's CPU time: each point's estimate (the recipe with that point's values), summed."""
    from .cost import minutes
    from .sweep_decl import override_text

    seconds = []
    for values in decl.points():
        texts = [*decl.fixed, *args.overrides, *(override_text(t, v) for t, v in values.items())]
        point = load_recipe(args.recipe, registry, texts, draft=args.draft, work=True, yes=True, limits=_limits(args))
        seconds.append(point.cost.cpu_seconds)
    return (
        f"sweep {decl.name}: {len(seconds)} points, ≈ {minutes(sum(seconds))} CPU in all "
        f"({minutes(min(seconds))} to {minutes(max(seconds))} each; cached steps are shared)"
    )


def _limits(args, outputs: tuple[str, ...] | None = None):
    """The limits a run enforces, as its arguments set them (``--max-minutes``) and the machine's available memory, for
    the nodes ``outputs`` (None: the recipe's outputs) and what they need."""
    from .cost import Limits, available_memory

    return Limits(max_seconds=60 * args.max_minutes, max_bytes=available_memory(), outputs=outputs)


def doc_summary(doc: str | None) -> str:
    """A docstring's first sentence, whole: its first paragraph joined into one line, cut at the first full
    stop followed by a capital (not inside "e.g. a node"; the full text is in `nodegraph describe`)."""
    import re

    paragraph = " ".join((doc or "").strip().split("\n\n")[0].split())
    end = re.search(r"\.\s+(?=[A-Z])", paragraph)
    return paragraph[: end.start() + 1] if end else paragraph


# a citation in a summary: "— SPEC §2.3 (G §3.2.2.2)", "(G eq. 6)", "(issue 25)", "G eq. 5", "(G's bunny)"
_CITATION = re.compile(
    r"\s+—\s+.*$"
    r"|\s*\([^()]*(?:\bSPEC\b|\beqs?\.|§|\bfig\.|\btable\b|\bissue \d|\b[GSU]'s\b)[^()]*\)"
    r"|\b(?:[A-Z]+ )?eqs?\. [\d–,]+\s*"
)
SUMMARY_WIDTH = 100  # characters of a summary in the listing before it is cut at a clause
_EQUATION = re.compile(r"\s*\[[^\]]*\]\s*=.*$")  # "swelling [x, y, z] = P·[r, s, t]": the words before it stay


def plain_summary(spec) -> str:
    """What a node type does, in words, for the one-line listing (``nodegraph nodes``): its module's opening
    sentence ("The ``rotate`` node: random rotation per P_num in a local uvw frame — SPEC §2.3 (…)") without the
    citations and equations, which ``describe`` shows with the rest; the implementation's first sentence, likewise
    cleaned, where the module does not open with the node's name (a module of several nodes, a plugin)."""
    module = sys.modules.get(spec.module)
    opening = doc_summary(getattr(module, "__doc__", None))
    named = re.match(
        rf"^(?:The ``{re.escape(spec.type_name)}`` node|Node ``{re.escape(spec.type_name)}``):\s*", opening
    )
    text = opening[named.end() :] if named else doc_summary(spec.doc)
    text = re.sub(r"\s*\(``[^`]*``\)", "", text)  # "(``cooked.cooked_material``)": a pointer into the code
    text = _EQUATION.sub("", _CITATION.sub("", text)).replace("``", "")
    text = text.replace(" ∪ ", " and ").replace(" → ", " into ").strip(" ,;:.")
    if len(text) > SUMMARY_WIDTH:  # a long one to its first clause that ends the thought
        cut = re.search(r", each |, so |; ", text[30:])
        text = text[: 30 + cut.start()] if cut else text
    return text[:1].upper() + text[1:] + "." if text else ""


def _cmd_nodes(args, registry) -> int:
    for spec in registry.specs():
        summary = plain_summary(spec)
        effects = f"  [effects: {', '.join(sorted(spec.effects))}]" if spec.effects else ""
        print(f"{spec.type_name:<18} {summary}{effects}")
    if not registry.names():
        print("(no node types found)")
    return 0


def _cmd_describe(args, registry) -> int:
    print(describe_command(args.first, args.second, registry), end="")
    return 0


def markdown_reference(registry) -> str:
    """Every node type as Markdown: doc, effects, ports and a parameter table (type, default, range, units)."""
    lines = ["# Node reference", "", "Generated by `nodegraph docs` from the node declarations.", ""]
    for spec in registry.specs():
        lines += [f"## `{spec.type_name}`", "", spec.doc or "", ""]
        facts = [f"module `{spec.module}`", "random" if spec.random else "deterministic"]
        if spec.effects:
            facts.append("effects: " + ", ".join(f"`{e}`" for e in sorted(spec.effects)))
        if not spec.store:
            facts.append("not cached (cheaper to compute again than to store)")
        lines += ["; ".join(facts), ""]
        for title, ports in (("Inputs", spec.inputs), ("Outputs", spec.outputs)):
            if ports:
                lines += [f"**{title}**", ""]
                lines += [
                    f"- `{n}`: {p.type_name}{' (optional)' if getattr(p, 'optional', False) else ''} — {p.doc}"
                    + (f" (columns: {', '.join(f'`{c}`' for c in p.columns)})" if getattr(p, "columns", ()) else "")
                    for n, p in ports.items()
                ]
                lines.append("")
        if spec.params:
            lines += ["| parameter | type | default | range | units | doc |", "|---|---|---|---|---|---|"]
            for name, param in spec.params.items():
                d = {k: v.replace("|", "\\|") for k, v in param.describe().items()}
                lines.append(f"| `{name}` | {d['type']} | {d['default']} | {d['range']} | {d['units']} | {d['doc']} |")
            lines.append("")
    return "\n".join(lines)


def _cmd_docs(args, registry) -> int:
    text = markdown_reference(registry)
    if args.out is None:
        print(text)
    else:
        from .cache import atomic_write

        if args.out.is_dir():
            raise NodegraphError(f"--out {args.out} is a directory; give a file name, e.g. {args.out / 'nodes.md'}")
        try:
            atomic_write(args.out, text.encode())
        except OSError as exc:
            raise NodegraphError(f"cannot write {args.out}: {exc.strerror or exc}") from None
        print(f"wrote {args.out}")
    return 0


def format_graph(recipe: Recipe, dot: bool = False) -> str:
    """The recipe's DAG as indented text, or as Graphviz DOT."""
    order = recipe.order()
    if dot:
        lines = [f'digraph "{recipe.name}" {{', "  rankdir=LR;", "  node [shape=box, fontname=Helvetica];"]
        for node_id in order:
            entry = recipe.nodes[node_id]
            family = f"\\n×{entry.family}" if entry.family else ""
            lines.append(f'  "{node_id}" [label="{node_id}\\n({entry.spec.type_name}){family}"];')
        for node_id in order:
            for port, wires in recipe.nodes[node_id].inputs.items():
                for wire in wires:
                    lines.append(f'  "{wire.node}" -> "{node_id}" [label="{wire.port}→{port}"];')
        lines.append("}")
        return "\n".join(lines)
    lines = [f"{recipe.name} (seed {recipe.seed}, effects: {', '.join(sorted(recipe.effects)) or 'none'})"]
    outputs = {w.node for w in recipe.outputs}
    for node_id in order:
        entry = recipe.nodes[node_id]
        family = f" ×{entry.family}" if entry.family else ""
        mark = "  ⇒ output" if node_id in outputs else ""
        lines.append(f"{node_id} ({entry.spec.type_name}{family}){mark}")
        for port, wires in entry.inputs.items():
            for wire in wires:
                lines.append(f"    {port} ← {wire}")
    return "\n".join(lines)


def _cmd_graph(args, registry) -> int:
    recipe = load_recipe(args.recipe, registry, args.overrides, draft=args.draft)
    print(format_graph(recipe, dot=args.dot))
    return 0


def _recipe_name(path: Path) -> str:
    """A recipe file's ``name:`` (its stem where it has none or cannot be read): enough to find its folders."""
    import yaml

    try:
        name = (yaml.safe_load(path.read_text(encoding="utf-8")) or {}).get("name")
    except (OSError, ValueError, AttributeError, yaml.YAMLError):
        name = None
    return name if isinstance(name, str) and name else path.stem


def _cmd_clean(args, registry) -> int:
    """List, then remove (not with --dry-run), what ``clean.prunable`` finds for the recipe; at a terminal only once
    the user says yes (``--yes``: without asking): a user's earlier results are theirs."""
    from .clean import prunable, remove

    if not args.recipe.is_file():
        raise NodegraphError(f"{args.recipe}: no such recipe file; give the recipe whose outputs to prune")
    found = prunable(args.recipe, _recipe_name(args.recipe))
    if not found.files and not found.manifests:
        print(f"nothing to prune: {args.recipe}'s output folders hold only its latest run's files")
        return 0
    ask = not args.dry_run and not args.yes and sys.stdin.isatty()
    for path, size in sorted(found.files.items()):
        print(f"{'would remove' if args.dry_run or ask else 'removing'} {path} ({format_size(size)})")
    done = "would free" if args.dry_run or ask else "freed"
    print(f"{done} {format_size(found.bytes)}: {len(found.files)} file(s) in {len(found.folders())} folder(s)")
    if ask and input("remove them? [y/N] ").strip().lower() not in ("y", "yes"):
        print("nothing removed")
        return 1
    if not args.dry_run:
        remove(found)
    return 0


def _prune_line(recipe_path: Path, name: str) -> str | None:
    """The one line a run says when earlier runs' outputs of its recipe can be pruned (``nodegraph clean``)."""
    from .clean import prunable

    found = prunable(recipe_path, name)
    if not found.files:
        return None
    return (
        f"earlier runs' outputs and partial recordings: {format_size(found.bytes)} in {len(found.files)} file(s); "
        f"nodegraph clean {recipe_path} --dry-run lists them, without --dry-run removes them"
    )


def _cmd_cache(args, registry) -> int:
    cache = Cache(args.cache_dir or default_cache_dir())
    if args.action == "clear":
        if not cache.directory.exists():
            print(f"nothing to clear: {cache.directory} does not exist")
            return 0
        if cache.directory.is_dir() and cache.is_cache() and not args.yes and sys.stdin.isatty():
            info = cache.info()
            answer = input(
                f"remove {info.entries} entries and {info.blobs} blobs ({info.bytes / 2**20:.1f} MiB) "
                f"from {cache.directory}? [y/N] "
            )
            if answer.strip().lower() not in ("y", "yes"):
                print("nothing removed")
                return 1
        cache.clear()
        print(f"cleared {cache.directory}")
        return 0
    if args.action == "limit" and args.size is not None:
        cache.set_limit(parse_size(args.size))
        _trim(cache, None, None)
    elif args.size is not None:
        raise NodegraphError(f"cache {args.action} takes no size (did you mean: nodegraph cache limit {args.size})")
    info = cache.info()
    limit = cache.limit()
    source = (
        f"${LIMIT_ENV_VAR}"
        if os.environ.get(LIMIT_ENV_VAR)
        else ("set with nodegraph cache limit" if (cache.directory / LIMIT_FILE).exists() else "the default")
    )
    print(
        f"cache {info.directory}: {info.entries} entries, {info.blobs} blobs, {format_size(info.bytes)} "
        f"of {format_size(limit)} ({source}); the least recently used results go first when a run ends above it"
    )
    # compiled kernels have a cache of their own, numba's (``numba_cache``): NODEGRAPH_CACHE does not move it
    print(f"compiled kernels: {os.environ.get('NUMBA_CACHE_DIR', '')} (numba's cache; $NUMBA_CACHE_DIR moves it)")
    return 0


def _trim(cache: Cache | None, since: float | None, reporter: Reporter | None) -> None:
    """Evict least recently used cache entries above the cache's size limit, sparing those used since
    ``since`` (the run that just ended), and say so in one line when it removed something or could not get under."""
    if cache is None or not cache.directory.exists():
        return
    done = cache.evict(spare_since=since)
    if reporter is None and done.entries:
        print(_eviction_line(done, cache))
    elif reporter is not None and (done.entries or done.over):
        reporter.warn("cache: " + _eviction_line(done, cache))


EVICTED_NAMED = 4  # steps named in the eviction line, the most evicted first; the rest are counted


def _eviction_line(done, cache: Cache) -> str:
    """What an eviction removed (how many results of which steps, and whose latest run lost some), what the cache
    holds of its limit and where, and how to raise the limit: a full cache no longer forgets work unsaid."""
    from collections import Counter

    limit, folder = format_size(cache.limit()), cache.directory.resolve()
    if done.entries:
        counts = Counter(done.nodes).most_common()
        steps = ", ".join(f"{node} ×{n}" if n > 1 else node for node, n in counts[:EVICTED_NAMED])
        if len(counts) > EVICTED_NAMED:
            steps += f" and {len(counts) - EVICTED_NAMED} more steps"
        lost = "".join(f"; the next nodegraph run {run} computes its own again" for run in done.runs)
        head = (
            f"removed {done.entries} least recently used entries ({format_size(done.freed)}: {steps}){lost}; the "
            f"cache now holds {format_size(done.left)} of its {limit} limit, in {folder}"
        )
    else:
        head = f"this run's results alone take {format_size(done.left)}, above the {limit} limit of {folder}"
    double = 2 * cache.limit()
    more = f"{-(-double // 2**30)}GiB" if double >= 2**30 else f"{-(-double // 2**20)}MiB"  # rounded up
    set_by = os.environ.get(LIMIT_ENV_VAR)
    raise_it = f"${LIMIT_ENV_VAR} (now {set_by})" if set_by else f"nodegraph cache limit {more} (or ${LIMIT_ENV_VAR})"
    return f"{head}; to keep more, raise it: {raise_it}"


def _interrupt(signum, frame):
    interrupt.stopping()
    raise KeyboardInterrupt


COMMANDS = {
    "run": _cmd_run,
    "watch": _cmd_watch,
    "sweep": _cmd_sweep,
    "check": _cmd_check,
    "nodes": _cmd_nodes,
    "describe": _cmd_describe,
    "graph": _cmd_graph,
    "cache": _cmd_cache,
    "clean": _cmd_clean,
    "docs": _cmd_docs,
    "inspect": _cmd_inspect,
}


def main(argv: list[str] | None = None) -> int:
    if argv is None:  # as a command, die quietly when the reader of a pipe goes away (| head)
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
        # SIGTERM (kill, a job scheduler) ends a run as Ctrl-C does: finished nodes stay cached and
        # the recording is closed as partial beside the last complete one
        signal.signal(signal.SIGTERM, _interrupt)
        # kill -USR1 PID prints every thread's stack to stderr and the run goes on: what a run that seems to hang
        # is doing, without a debugger (the forked child inherits it)
        if hasattr(signal, "SIGUSR1"):
            import faulthandler

            faulthandler.register(signal.SIGUSR1, all_threads=True)
    args = build_parser().parse_args(argv)
    interrupt.said_command(sys.argv[1:] if argv is None else list(argv))  # what a stopped run says to type again
    runtime.configure()  # numba's kernel cache, before any node imports a kernel module (and before the fork)
    if argv is None and args.command in ("run", "sweep", "watch"):
        # in a child that a signal stops within interrupt.GRACE seconds, whatever its node is doing
        # (watch stops its own steps with SIGINT: only a signal to the supervisor is a stop there)
        status = interrupt.supervise(child_signals=args.command != "watch")
        if status is not None:  # the child has ended: the parent's interpreter tear-down (0.2 s under load) is not due
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(status)
    try:
        registry = default_registry(plugins=args.plugin) if args.command not in ("cache", "inspect", "clean") else None
        return COMMANDS[args.command](args, registry)
    except RecipeError as exc:  # plain text: a terminal-width wrap would split file:line:column
        print(str(exc), file=sys.stderr)
        return 2
    except NodeFailure as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except NodegraphError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(interrupt.stopped_line(), file=sys.stderr, flush=True)
        interrupt.said()  # a supervisor that ends this process during its clean-up says nothing more
        interrupt.leave(130)  # a supervised child: at once, no interpreter tear-down
        return 130


if __name__ == "__main__":
    sys.exit(main())
