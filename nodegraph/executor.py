"""Pull-based execution: compute only what the requested outputs need, reuse what the cache holds.

What runs and under which cache key is planned first (``plan``); then each instance is loaded from the
cache or computed, pulling its inputs, and logged to the run's recording.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Protocol

from . import __version__, codec, interrupt, node_times, runtime
from .blueprint import LOG, build_blueprint
from .cache import Cache, Fragment, atomic_write
from .checkpoint import Checkpoint
from .compile_ahead import CompileAhead, mark_compiled
from .compile_progress import CompileWatch
from .context import Context, EntityLogger
from .errors import CacheCorruption, NodeFailure, NodegraphError
from .output_files import (
    MANIFEST,
    current_outputs,
    earlier_outputs,
    settle_earlier,
    write_manifest,
    write_output,
)
from .plan import Instance, Plan, RecipeRef, plan_jobs
from .recipe import Recipe, Wire, nearest
from .report import NodeRecord, PeakMemory, Reporter, bar_label, now
from .rerun_log import NodeCapture, RunRecording, dispatch_digest, log_value, logger_digest, remove_stale_partials

OVERLAP_ENV = "NODEGRAPH_OVERLAP"  # off: every node in turn, none beside another (``Beside``)


@dataclass
class RunResult:
    """What a run produced: values of materialised instances, per-node records, files written."""

    recipe: Recipe
    keys: dict[Instance, str]
    values: dict[Instance, dict[str, Any]]
    records: list[NodeRecord]
    files: list[Path] = field(default_factory=list)
    rrd: Path | None = None
    executor: Executor | None = field(default=None, repr=False)  # loads what a run with current outputs skipped
    current: bool = False  # the files and recording were already as this run would write them: none written

    def output(self, ref: str) -> Any:
        """The value of ``node.port`` (a list, one per variant, for a variant family)."""
        node_id, _, port = ref.partition(".")
        entry = self.recipe.nodes[node_id]
        port = port or next(iter(entry.spec.outputs))
        if entry.family is None:
            return self._value(Instance(node_id))[port]
        return [self._value(Instance(node_id, v))[port] for v in range(entry.family)]

    def _value(self, inst: Instance) -> dict[str, Any]:
        if inst not in self.values and self.executor is not None:
            return self.executor.materialise(inst)
        return self.values[inst]

    def status(self) -> dict[str, str]:
        return {r.node: r.status for r in self.records}


class LiveSession(Protocol):
    """What a long-lived caller (``nodegraph watch``) lends each run: ``kept``, values by cache key held between
    runs (used before the cache, filled with this run's); ``started(inst, key)``, called as an instance is about
    to run, its inputs in hand (the watch stops a run there once an edit has made that instance unneeded);
    ``ran(inst)``, called as soon as an instance that ran is in the recording (or computed, without one)."""

    kept: dict[str, dict[str, Any]]

    def started(self, inst: Instance, key: str) -> None: ...

    def ran(self, inst: Instance) -> None: ...


class Executor:
    """Runs one recipe against one cache, logging to one recording."""

    def __init__(
        self,
        recipe: Recipe,
        cache: Cache | None = None,
        reporter: Reporter | None = None,
        recording: RunRecording | None = None,
        max_seconds: float | None = None,
        session: LiveSession | None = None,
        overlap: bool = True,
    ):
        """``session``: what a long-lived caller (``nodegraph watch``) lends each run (``LiveSession``);
        ``overlap``: a node declared ``overlap`` runs while a second thread computes the instances independent of
        it (``Beside``; never with a session: its callbacks and the values it keeps expect one thread)."""
        self.recipe = recipe
        self.kept = None if session is None else session.kept
        self.on_ran = None if session is None else session.ran
        self.on_start = None if session is None else session.started
        self.max_seconds = max_seconds
        self.cache = cache
        self.reporter = reporter or Reporter(quiet=True)
        self.recording = recording
        self.planned = Plan(recipe)
        self.keys: dict[Instance, str] = self.planned.keys  # filled by ``plan``
        self.values: dict[Instance, dict[str, Any]] = {}
        self.status: dict[Instance, NodeRecord] = {}
        self.sources: dict[Path, tuple[str, str]] = {}  # each file written: the step it came from and its key
        self.hits: set[str] = set()
        self.ran_elsewhere: dict[str, NodeRecord] = {}  # by cache key: instances a pool computed for this run
        self.logged: set[Instance] = set()  # instances whose logs are in the recording
        self.overlap = overlap
        self._beside: Beside | None = None
        self.lane = threading.local()  # ``side``: this thread computes the instances beside a node (``Beside``)
        self.estimate = None  # the recipe's cost estimate (``cost.Estimate``): the bar's ETA where no time is kept
        self.warned: set[str] = set()  # what this run's nodes warned of (``Context.warn``): each said once

    # planning ---------------------------------------------------------------------------------
    def plan(self, node_ids) -> list[Instance]:
        """Cache keys (in ``keys``) for every instance of the given nodes and the nodes they need, in
        topological order."""
        return self.planned.add(node_ids)

    # running ----------------------------------------------------------------------------------
    def run(self, outputs: list[Wire] | None = None) -> RunResult:
        """Materialise the requested outputs (default: the recipe's) and everything they need."""
        runtime.configure()  # numba's kernel cache, before the nodes import their kernel modules
        outputs = list(outputs or self.recipe.outputs)
        order = self.plan({w.node for w in outputs})
        if self.cache is not None:
            self.hits = {key for key in set(self.keys.values()) if self.cache.has(key)}
            # used by this run, loaded or not (the upstream of a cached step): marked now, not as the run ends, so
            # the trim after a run that stops or fails (``Cache.evict``, sparing what a run used) keeps them too
            for key in {self.keys[inst] for inst in order} & self.hits:
                self.cache.touch(key)
        output_nodes = {w.node for w in outputs}
        # cached instances go into the recording after every instance that runs: what an edit changed reaches
        # the recording (and a viewer streaming it) first; the order of chunks in a recording carries no meaning
        later: list[Instance] = []

        def visit(inst: Instance) -> None:
            if inst in self.status:
                return
            if not self.recipe.nodes[inst.node].spec.store and self.recording is None and inst.node not in output_nodes:
                return  # never cached: computed when a step that runs pulls it (``materialise``), not for nothing
            if self.keys[inst] in self.hits and inst.node not in output_nodes:
                if self.recording is not None:
                    later.append(inst)
                    return
                if self._skip_load(inst):
                    return
            self.materialise(inst)
            if self.recording is not None and inst not in self.logged:
                later.append(inst)  # loaded, not run

        self._beside = self._plan_beside(order, visit)
        if self._beside is not None:
            order = self._beside.order
        ahead = None
        if not self.ran_elsewhere:  # kernels of the later instances compile in a second process meanwhile
            to_run = {inst for inst in order if self.keys[inst] not in self.hits}
            ahead = CompileAhead.start(self.recipe, order, to_run)
        times = {} if self.cache is None else node_times.load(self.cache.directory, self.recipe.name)
        plan = node_times.planned([(i.node, i.label, self.keys[i] in self.hits) for i in order], times, self.estimate)
        try:
            with self.reporter.task(
                bar_label(self.recipe.name, [i.node for i in order]), len(order), plan=plan
            ) as tick:
                for position, inst in enumerate(order):
                    tick()
                    if ahead is not None:
                        ahead.reached(position)
                    visit(inst)
                for inst in later:
                    if inst in self.logged:
                        continue
                    if inst not in self.status and self._skip_load(inst):
                        continue
                    self.materialise(inst)
                    self._log_cached(inst)
        except KeyboardInterrupt:  # stopped: its partial recording is removed, nothing more goes into it
            raise
        except BaseException:
            for inst in later:  # what the failed run had in hand still goes into its partial recording
                if inst not in self.logged and inst not in self.status:
                    try:
                        self._skip_load(inst)
                    except Exception:  # the node's own error is the one to report
                        break
            raise
        finally:
            if ahead is not None:
                ahead.close()
            for inst in order:
                elsewhere = self.ran_elsewhere.get(self.keys[inst])
                if elsewhere is not None and inst in self.status and self.status[inst].status == "cached":
                    self.status[inst] = replace(elsewhere, log_seconds=self.status[inst].log_seconds)
                if inst in self.status:
                    self.reporter.record(self.status[inst])
            if self.cache is not None:  # what the next run's progress bar expects
                node_times.remember(self.cache.directory, self.recipe.name, [self.status[i] for i in self.status])
        for inst in order:  # complete: what a stopped run would have resumed with is not needed any more
            if not self.recipe.nodes[inst.node].spec.store and self.cache is not None:
                self._unstored_checkpoint(inst).clear()
        if ahead is None and any(s.status == "ran" for s in self.status.values()):
            mark_compiled(self.recipe)  # every kernel in hand: the next estimate says none is left to compile
        return RunResult(self.recipe, dict(self.keys), self.values, [self.status[i] for i in order if i in self.status])

    def reuse(self, outputs: list[Wire], directory: Path, rrd: Path | None, key: str) -> RunResult | None:
        """The run's result without loading or writing anything, when every instance the outputs need is
        cached and the files (and recording) a run with the same ``output_key`` wrote are still there as it
        left them (``output_files.current_outputs``); None otherwise. Values load on demand (``output``)."""
        order = self.plan({w.node for w in outputs})
        keys = {self.keys[inst] for inst in order if self.recipe.nodes[inst.node].spec.store}  # the rest: never
        if self.cache is None or not all(self.cache.has(k) for k in keys):
            return None
        files = current_outputs(directory, key, rrd)
        if files is None:
            return None
        for k in keys:
            self.cache.touch(k)  # used by this run: the last to go when the cache is trimmed
        if rrd is not None:  # what interrupted runs left beside the recording: this complete run ends it
            remove_stale_partials(rrd)
        records = [NodeRecord(i.label, self.recipe.nodes[i.node].spec.type_name, "cached") for i in order]
        for inst in order:
            self._say(inst, self.cache.warnings(self.keys[inst]))
        with self.reporter.task(bar_label(self.recipe.name, [i.node for i in order]), len(order)) as tick:
            for record in records:
                tick()
                self.reporter.record(record)
        return RunResult(self.recipe, dict(self.keys), self.values, records, files, rrd, self, current=True)

    def output_key(self, outputs: list[Wire], rrd: Path | None) -> str:
        """What the files and recording of a run depend on: the recipe, the requested outputs, the cache
        key of every instance they need, the engine's code, the output writers' and (with a recording)
        the Rerun loggers' code. Equal keys: equal bytes, so current files need not be written again."""
        import hashlib
        import json

        from .code_digest import module_digest

        order = self.plan({w.node for w in outputs})
        payload = {
            "recipe": self.recipe.digest(),
            "outputs": [str(w) for w in outputs],
            "instances": [self.keys[inst] for inst in order],
            "engine": module_digest(__name__, {__name__.partition(".")[0]}),
            "writers": dispatch_digest(write_output),
            "recording": None if rrd is None else logger_digest(),
        }
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()

    def materialise(self, inst: Instance) -> dict[str, Any]:
        """The outputs of ``inst``: from memory, from the cache, or by running the node (pulling inputs)."""
        if inst in self.values:
            return self.values[inst]
        entry = self.recipe.nodes[inst.node]
        spec = entry.spec
        key = self.keys[inst]
        status = "ran"
        if self.kept is not None and key in self.kept:  # held in memory by the caller since an earlier run
            self.values[inst] = self.kept[key]
            self.status.setdefault(inst, NodeRecord(inst.label, spec.type_name, "cached", 0.0))
            return self.values[inst]
        if key in self.hits:
            start = now()
            try:
                outputs = self.cache.load(key, {p: o.type for p, o in spec.outputs.items()})
            except CacheCorruption as exc:
                self.reporter.warn(f"cache entry of node '{inst.label}' is corrupt ({exc}); recomputing")
                self.cache.discard(key)
                self.hits.discard(key)
                status = "recomputed (corrupt cache)"
            else:
                self.values[inst] = outputs
                if self.kept is not None:
                    self.kept[key] = outputs
                self.status.setdefault(inst, NodeRecord(inst.label, spec.type_name, "cached", now() - start))
                self._say(inst, self.cache.warnings(key))
                return outputs

        if not spec.store and self._resumed(inst):
            return self.values[inst]
        kwargs = self._arguments(inst)
        if self.on_start is not None:
            self.on_start(inst, key)
        capture = None
        if self.recording is not None:  # the node's logs and outputs go to a fragment, kept with its entry
            capture = self.recording.capture(self._capture_path(key))
        ctx = self._context(
            inst,
            # the node's own logging under /<node>/log: never at an output's path, where the static output
            # (the final state) would shadow what the node logged on a timeline (a simulation per step)
            rerun=capture.logger(f"{inst.entity}/{LOG}") if capture else EntityLogger(None, inst.entity),
            reporter=self.reporter,
            max_seconds=self.max_seconds,
            checkpoint=None if self.cache is None else Checkpoint(self.cache.directory / "checkpoints" / f"{key}.npz"),
        )
        beside = self._beside if self._beside is not None and self._beside.main == inst else None
        side = getattr(self.lane, "side", False)
        clock = time.thread_time if side else time.process_time  # beside a node: this thread's own CPU
        start, cpu_start = now(), clock()
        # the kernel's high-water mark is the process's: reset by one thread, it would cut the other's short
        memory = PeakMemory() if not side else contextlib.nullcontext()
        # numba's compile events are the process's: the instances beside this one report their own
        watch = CompileWatch(self.reporter, inst.label) if beside is None else contextlib.nullcontext()
        interrupt.step_started(inst.label, None if ctx.checkpoint is None else ctx.checkpoint.path)
        self.reporter.step_started(inst.label)
        ok = stopped = False
        try:
            with memory, watch:
                result = (
                    spec.run(ctx, **kwargs)
                    if beside is None
                    else beside.run(lambda: spec.run(ctx, **kwargs), None if spec.overlap is True else spec.overlap)
                )
            outputs = self._check_outputs(spec, result)
            ok = True
        except BaseException as exc:
            if capture is not None:  # what the node logged before it stopped goes into the partial recording
                self._append_unfinished(inst, capture)
            if not isinstance(exc, Exception):  # Ctrl-C, SIGTERM: the run stops here
                stopped = True
                raise
            if interrupt.stopped_by(exc):  # the stop's doing, come out of compiled code as another error
                stopped = True
                raise KeyboardInterrupt from exc
            elapsed = now() - start if beside is None or beside.elapsed is None else beside.elapsed
            self.status[inst] = NodeRecord(inst.label, spec.type_name, "failed", elapsed)
            if isinstance(exc, NodeFailure):
                raise
            raise NodeFailure(inst.node, spec.type_name, exc, inst.variant, self._where(inst)) from exc
        finally:
            if ctx.rerun.enabled:
                ctx.rerun.reset_time()
            if not stopped:  # a stopped step stays named as running: the 'interrupted' line names it
                interrupt.step_ended(inst.label)
                took = beside.elapsed if beside is not None and beside.elapsed is not None else now() - start
                self.reporter.step_ended(inst.label, took, ok)
        elapsed, cpu = now() - start, clock() - cpu_start
        if beside is not None:  # its own wall, not the wait for the instances beside it; the CPU they took, less
            elapsed, cpu = beside.elapsed, cpu - beside.cpu
        for value in outputs.values():
            codec.freeze(value)
        self.values[inst] = outputs
        if self.kept is not None:
            self.kept[key] = outputs
        peak = memory.peak_bytes if isinstance(memory, PeakMemory) else None
        self.status[inst] = NodeRecord(inst.label, spec.type_name, status, elapsed, peak, cpu_seconds=cpu)
        self._say(inst, ctx.warnings)
        stop = fragment = None
        try:  # logged first, so the recording and a viewer get it before the cache keeps it
            fragment = self._log_ran(inst, capture, outputs)
            if self.on_ran is not None:
                self.on_ran(inst)
        except KeyboardInterrupt as exc:  # a stop while it is logged: the finished step is stored, then it stops
            stop, fragment = exc, None
        try:
            # stored whole before a stop is honoured: one that comes meanwhile is raised as the hold ends
            with interrupt.Hold(inst.label):
                if self.cache is not None:
                    ctx.checkpoint.clear()  # the outputs are stored: no progress to resume any more
                    if spec.store:
                        said, quick = ctx.warnings, stop is not None
                        self.cache.store(key, outputs, inst.node, spec.type_name, elapsed, fragment, quick, said)
                    elif self.kept is None:  # never cached: kept as its checkpoint until the run completes
                        atomic_write(self._unstored_checkpoint(inst).path, codec.encode(outputs), durable=False)
        finally:
            if capture is not None:  # moved into the cache by store; without a cache, not needed any more
                capture.path.unlink(missing_ok=True)
        if stop is not None:
            raise stop
        if beside is not None and beside.error is not None:  # an instance beside it failed: this one is stored
            raise beside.error
        return outputs

    def _unstored_checkpoint(self, inst: Instance) -> Checkpoint:
        """Where a run keeps the outputs of a never-cached step (``store=False``: a scene made in a second, too large
        to cache) it computed until it completes: the step's checkpoint file (``checkpoints/<key>.npz``, written as
        the step ends, undeflated and not flushed: a torn one fails to decode and the step is computed), so a
        stopped run's re-run resumes with them, and removes it, rather than computing a finished step again (a stop
        in a step of native code, a render, may leave no time to write it then)."""
        return Checkpoint(self.cache.directory / "checkpoints" / f"{self.keys[inst]}.npz")

    def _resumed(self, inst: Instance) -> bool:
        """Whether a never-cached step's outputs were taken from the checkpoint a run that did not complete kept of
        them, which goes once read: the step finished in that run, so it is not computed again."""
        if self.cache is None:
            return False
        checkpoint = self._unstored_checkpoint(inst)
        start, outputs = now(), checkpoint.load()
        spec = self.recipe.nodes[inst.node].spec
        if not isinstance(outputs, dict) or set(outputs) != set(spec.outputs):
            return False
        checkpoint.clear()
        for value in outputs.values():
            codec.freeze(value)
        self.values[inst] = outputs
        self.status.setdefault(inst, NodeRecord(inst.label, spec.type_name, "cached", now() - start))
        if self.recording is not None:  # into the recording as a run of it logs it: it is never cached
            capture = self.recording.capture(self._capture_path(self.keys[inst]))
            try:
                self._log_ran(inst, capture, outputs)
            finally:
                capture.path.unlink(missing_ok=True)
        return True

    def _log_ran(self, inst: Instance, capture, outputs: dict[str, Any]) -> Fragment | None:
        """Log a computed instance's outputs into its capture and append that fragment to the recording, as a
        cached re-run will put it; the fragment (None without a recording)."""
        if capture is None:
            return None
        log_start = now()
        fragment = self._capture_outputs(inst, capture, outputs)
        self._append(inst, fragment, capture.live)
        self.status[inst].log_seconds = now() - log_start
        return fragment

    def _plan_beside(self, order: list[Instance], visit: Callable[[Instance], None]) -> Beside | None:
        """The first instance to run of a node declared ``overlap`` and the run's order with what it needs pulled
        ahead of it; None when there is none, or nothing to compute beside it."""
        if not self.overlap or self.kept is not None or self.ran_elsewhere:
            return None
        main = next(
            (i for i in order if self.recipe.nodes[i.node].spec.overlap and self.keys[i] not in self.hits), None
        )
        if main is None:
            return None
        before: set[Instance] = set()
        stack = [main]
        while stack:
            for src, _ in (pair for pairs in self.planned.sources(stack.pop()).values() for pair in pairs):
                if src not in before:
                    before.add(src)
                    stack.append(src)
        after = {main}
        for inst in order:
            if any(src in after for pairs in self.planned.sources(inst).values() for src, _ in pairs):
                after.add(inst)
        side = [i for i in order if i not in before and i not in after]
        if not any(self.keys[i] not in self.hits for i in side):
            return None
        ahead = [i for i in order if i in before]
        return Beside(main, [*ahead, main, *(i for i in order if i not in before and i != main)], side, visit, self)

    def _arguments(self, inst: Instance) -> dict[str, Any]:
        """The keyword arguments ``inst``'s node is called with: its inputs (pulled) and its parameters."""
        entry = self.recipe.nodes[inst.node]
        sources = self.planned.sources(inst)
        kwargs: dict[str, Any] = {}
        for port_name, port in entry.spec.inputs.items():
            values = [self.materialise(src)[out] for src, out in sources.get(port_name, [])]
            kwargs[port_name] = values if port.many else (values[0] if values else None)
        kwargs.update(entry.params)
        return kwargs

    def rehearse(self, inst: Instance) -> None:
        """Run ``inst`` again on its inputs in hand (``kept``, else the cache), its outputs dropped and nothing
        logged or stored: what a node's first run in a process pays (imports, kernels loaded from numba's
        cache, what it derives from its inputs, ``codec.derived``) is paid now, not by the next edit
        (``nodegraph watch`` between saves). Its inputs must be in ``kept`` or the cache."""
        spec = self.recipe.nodes[inst.node].spec
        kwargs = self._arguments(inst)
        spec.run(self._context(inst, rerun=EntityLogger(None, inst.entity)), **kwargs)

    def _context(self, inst: Instance, **more: Any) -> Context:
        """The ``Context`` a run of ``inst`` gets: its node, seed, effects and variant, and ``more``."""
        spec = self.recipe.nodes[inst.node].spec
        return Context(
            node_id=inst.node,
            node_type=spec.type_name,
            seed=self.planned.seed(inst),
            effects=frozenset(spec.effects & self.recipe.effects),
            variant=inst.variant,
            **more,
        )

    def _capture_path(self, key: str) -> Path:
        """Where a node's capture is written: beside its cache entry, or a temporary file without a cache."""
        if self.cache is not None:
            return self.cache.capture_path(key)
        fd, tmp = tempfile.mkstemp(prefix="nodegraph-", suffix=".rrd")
        os.close(fd)
        interrupt.note(tmp)
        return Path(tmp)

    def _capture_outputs(self, inst: Instance, capture: NodeCapture, outputs: dict[str, Any]) -> Fragment:
        """Log each output of ``inst`` into ``capture`` (at ``/<node>[/<variant>]/<port>``) and close it."""
        for port, value in outputs.items():
            log_value(value, capture.logger(f"{inst.entity}/{port}"))
        return capture.close(inst.entity, self.recording.loggers)

    def _append_unfinished(self, inst: Instance, capture: NodeCapture) -> None:
        """Append what a node that failed or was interrupted had logged, then remove its capture (a capture
        that cannot be read is reported, never put in place of the node's own error)."""
        try:
            self._append(inst, capture.close(inst.entity, self.recording.loggers), capture.live)
        except Exception as exc:
            self.reporter.warn(f"node '{inst.label}': what it logged before it stopped is lost ({exc})")
        finally:
            capture.path.unlink(missing_ok=True)

    def _append(self, inst: Instance, fragment: Fragment, live: bool) -> None:
        self.recording.append(fragment.path, inst.entity, fragment.logged, fragment.entity, live)
        self.logged.add(inst)

    def _skip_load(self, inst: Instance) -> bool:
        """Record a cached instance without loading its values, when only the recording would want them
        and its entry keeps what it logged (appended as it is). False: it must be loaded."""
        start = now()
        fragment = None if self.recording is None else self._kept_fragment(inst)
        if self.recording is not None and fragment is None:
            return False
        record = NodeRecord(inst.label, self.recipe.nodes[inst.node].spec.type_name, "cached")
        if fragment is not None:
            self._append(inst, fragment, live=False)
            record.log_seconds = now() - start
        self.status[inst] = record
        self._say(inst, self.cache.warnings(self.keys[inst]))
        return True

    def _say(self, inst: Instance, warnings: list[str]) -> None:
        """Say what ``inst``'s node warned of (``Context.warn``), each message once a run (a family's instances
        reading one file say it once), under the node's id."""
        for message in warnings:
            if message not in self.warned and self.reporter is not None:
                self.warned.add(message)
                self.reporter.warn(f"{inst.node}: {message}")

    def _kept_fragment(self, inst: Instance) -> Fragment | None:
        try:
            return self.cache.fragment(self.keys[inst], self.recording.loggers)
        except CacheCorruption as exc:
            self.reporter.warn(f"node '{inst.label}': {exc}; logging its outputs again")
            return None

    def _log_cached(self, inst: Instance) -> None:
        """Put a loaded cached instance into the recording: the fragment kept with its entry; for an entry
        without one (computed by a worker, or by a run with no recording) or with a damaged one, its outputs
        are logged into a new fragment, kept with the entry for the next run. A value held in memory (``kept``)
        whose entry has gone since (the cache trimmed or cleared) is stored again, with that fragment."""
        key = self.keys[inst]
        start = now()
        fragment = self._kept_fragment(inst)
        if fragment is None:
            capture = self.recording.capture(self.cache.capture_path(key))
            try:
                self._carry_run_logs(inst, capture)
                made = self._capture_outputs(inst, capture, self.values[inst])
                if self.cache.has(key):
                    self.cache.add_fragment(key, made)
                else:
                    spec = self.recipe.nodes[inst.node].spec
                    self.cache.store(key, self.values[inst], inst.node, spec.type_name, fragment=made)
            finally:
                capture.path.unlink(missing_ok=True)  # a leftover only if add_fragment did not move it
            fragment = replace(made, path=self.cache.fragment_path(key))
        self._append(inst, fragment, live=False)
        self.status[inst].log_seconds = now() - start

    def _carry_run_logs(self, inst: Instance, capture: NodeCapture) -> None:
        """Into a new fragment of a cached instance, what the node logged as it ran (``/<node>/log/…``, e.g. a
        simulation step by step) from the fragment the entry kept, when only the loggers of its outputs changed:
        that part is the node's own code, which the entry's key covers, and cannot be logged again without
        running the node."""
        try:
            old = self.cache.fragment(self.keys[inst], None)
        except CacheCorruption:
            return
        if old is None:
            return
        from rerun.chunk import RrdReader

        chunks = RrdReader(str(old.path)).stream().filter(content=f"{old.entity}/{LOG}/**")
        if old.entity != inst.entity:  # an identical node elsewhere in the recipe logged it
            cut = len(old.entity)
            chunks = chunks.map(lambda chunk: chunk.with_entity_path(inst.entity + chunk.entity_path[cut:]))
        capture.stream.send_chunks(chunks)
        ran = {sub: kinds for sub, kinds in old.logged.items() if sub == f"/{LOG}" or sub.startswith(f"/{LOG}/")}
        capture.index.add_relative(inst.entity, ran)

    def _where(self, inst: Instance):
        return self.recipe.source.at(("nodes", inst.node), key=True)

    @staticmethod
    def _check_outputs(spec, result) -> dict[str, Any]:
        """The node's result as {port: value}: a dict naming every output, or the bare value of a single one."""
        if not (isinstance(result, dict) and set(result) == set(spec.outputs)):
            if len(spec.outputs) != 1:
                got = sorted(result) if isinstance(result, dict) else type(result).__name__
                raise TypeError(f"node returned {got}; declared outputs are {sorted(spec.outputs)}")
            result = {next(iter(spec.outputs)): result}
        for port, value in result.items():
            declared = spec.outputs[port].type
            if not isinstance(value, declared):
                raise TypeError(f"output '{port}' is a {type(value).__name__}, declared {declared.__name__}")
        return result

    # writing ----------------------------------------------------------------------------------
    def write_outputs(self, result: RunResult, outputs: list[Wire], directory: Path) -> list[Path]:
        """Write each requested output under ``directory`` (families into a sub-folder per output)."""
        directory.mkdir(parents=True, exist_ok=True)
        written = []
        for wire in outputs:
            entry = self.recipe.nodes[wire.node]
            stem = wire.node if len(entry.spec.outputs) == 1 else f"{wire.node}.{wire.port}"
            for inst in self.planned.instances(wire.node):
                value = self.materialise(inst)[wire.port]
                if inst.variant is None:
                    paths = write_output(value, directory, stem)
                else:
                    folder = directory / stem
                    folder.mkdir(exist_ok=True)
                    paths = write_output(value, folder, f"{inst.variant:03d}")
                written += paths
                self.sources.update((path, (inst.label, self.keys[inst])) for path in paths)
        result.files = written
        return written


class Beside:
    """A node declared ``overlap`` (``main``: its work in native threads, the GIL released, no numba kernel) runs in
    the main thread while a second thread computes ``side``, the instances that neither need it nor depend on it,
    in the run's order (``visit``: as the main loop would, cache and recording included). The main thread does
    nothing else meanwhile: the executor's state has one writer at a time, and the node itself stays in the main
    thread, where a signal can stop it (Mitsuba cancels its render on SIGINT there; from any other thread the
    process aborted). Numba's parallel kernels (its ``workqueue`` layer aborts when two threads launch at once)
    only ever run in the second thread then. ``run`` returns once both are done; if ``main`` fails, the second
    thread stops after the instance it is computing. ``elapsed``: the node's own wall time; ``cpu``: the second
    thread's CPU seconds (the node's CPU is the process's less this one; each instance beside it gets its thread's
    own, so numba worker threads those instances start count to the node). The policy it belongs to: ``runtime``."""

    def __init__(self, main: Instance, order: list[Instance], side: list[Instance], visit, executor: Executor):
        self.main, self.order, self.side, self.visit = main, order, side, visit
        self.executor = executor
        self.error: BaseException | None = None
        self.elapsed: float | None = None
        self.cpu = 0.0
        self._stop = threading.Event()

    def run(self, body: Callable[[], Any], prepare: Callable[[], None] | None = None) -> Any:
        """``body()`` in this thread, ``side`` in a second one started after ``prepare()`` (the node's native
        libraries loaded: ``NodeSpec.overlap``) and the ``NodeSpec.libraries`` of the nodes in ``side``."""
        thread = threading.Thread(target=self._compute_side, name="nodegraph-beside")
        start = now()
        if prepare is not None:
            prepare()
        specs = (self.executor.recipe.nodes[inst.node].spec for inst in self.side)
        for load in dict.fromkeys(spec.libraries for spec in specs if spec.libraries is not None):
            load()  # what the second thread's nodes open, opened here (``NodeSpec.libraries``)
        thread.start()
        ok = False
        try:
            result = body()
            ok = True
        finally:
            self.elapsed = now() - start
            if not ok:
                self._stop.set()
            try:
                thread.join()
            except BaseException:  # Ctrl-C while waiting: the second thread stops after its instance
                self._stop.set()
                raise
        return result

    def _compute_side(self) -> None:
        self.executor.lane.side = True
        cpu = time.thread_time()
        try:
            for inst in self.side:
                if self._stop.is_set():
                    break
                self.visit(inst)
        except BaseException as exc:
            self.error = exc
        finally:
            self.cpu = time.thread_time() - cpu


def run_recipe(
    recipe: Recipe,
    *,
    outputs: list[str] | None = None,
    cache: Cache | None = None,
    out_dir: Path | None = None,
    rrd: Path | None = None,
    spawn: bool = False,
    reporter: Reporter | None = None,
    max_seconds: float | None = None,
    pool=None,
    plugins=(),
    session: LiveSession | None = None,
    estimate=None,
) -> RunResult:
    """Run a validated recipe: pull the outputs, log to ``rrd``, write files under ``out_dir``; a node
    that expects to run longer than ``max_seconds`` refuses to start (``Context.expect_cost``).
    ``session``: see ``LiveSession``; ``estimate``: the recipe's cost estimate (``cost.Estimate``), what the
    progress bar expects of a node that has not run before (``node_times.planned``).

    With a ``pool`` (``pool.InstancePool``, e.g. ``dask_pool.DaskPool``) the node instances missing from
    the cache are computed by its workers first (``plugins``: the plugin files they load); the run then
    finds them in the cache, and its closing table shows the workers' wall times.

    The recording is written beside ``rrd`` as ``*.<pid>.partial.rrd`` and moved over ``rrd`` only when the run
    completes; its id is derived from what the recipe computes (``Recipe.digest``), so two settings of a
    recipe are two recordings a viewer shows side by side, and it carries a blueprint built from the
    recipe and what was logged (``blueprint``)."""
    wires = resolve_outputs(recipe, outputs) if outputs else list(recipe.outputs)
    warn = reporter.warn if reporter is not None else None
    overlap = os.environ.get(OVERLAP_ENV, "on") != "off"
    executor = Executor(recipe, cache, reporter, None, max_seconds, session, overlap=overlap)
    executor.estimate = estimate
    interrupt.run_began(cached=cache is not None)
    key = None if out_dir is None else executor.output_key(wires, rrd)
    if key is not None and not spawn:  # a viewer to stream to needs the run itself
        reused = executor.reuse(wires, out_dir, rrd, key)
        if reused is not None:
            _warn_others(out_dir, reused.files, warn)
            return reused
    if rrd is not None:
        executor.recording = RunRecording(
            rrd, recording_name(recipe), spawn=spawn, warn=warn, recording_id=recording_id(recipe)
        )
    recording = executor.recording
    ok = stopped = False
    try:
        if pool is not None:
            executor.ran_elsewhere = compute_in_pool(pool, recipe, wires, cache, plugins, reporter, max_seconds)
        result = executor.run(wires)
        if out_dir is not None:
            executor.write_outputs(result, wires, out_dir)
        ok = True
    except KeyboardInterrupt:  # Ctrl-C, SIGTERM: stopped on purpose, its partial recording is not wanted
        stopped = True
        raise
    finally:
        if recording is not None:
            blueprint = build_blueprint(recipe, recording.index) if ok else None
            written = recording.close(complete=ok, blueprint=blueprint)
            if ok:
                result.rrd = written
            elif stopped:
                written.unlink(missing_ok=True)
            elif warn is not None:
                kept = (
                    f"the last complete recording {recording.path} was left as it was"
                    if Path(recording.path).exists()
                    else f"no complete recording {recording.path} exists yet"
                )
                warn(f"the run did not complete: what it recorded is in {written}; {kept}")
    if out_dir is not None:
        writers = dispatch_digest(write_output)
        earlier, removed = settle_earlier(out_dir, result.files, recipe.digest(), _current_key(recipe), writers)
        if removed and reporter is not None:
            reporter.tell(stale_line(out_dir, removed))
        write_manifest(
            out_dir,
            result.files,
            {
                "recipe": recipe.name,
                "recipe_file": str(Path(recipe.path).resolve()),  # output_folder: the folder's recipe file
                "digest": recipe.digest(),
                "output_key": key,
                "seed": recipe.seed,
                "overrides": list(recipe.overrides),
                "outputs": [str(w) for w in wires],
                "engine": __version__,
                "writers": writers,
                "written": datetime.now(UTC).isoformat(timespec="seconds"),
            },
            recording=result.rrd,
            earlier=earlier,
            sources=executor.sources,
        )
        _warn_others(out_dir, result.files, warn)
    return result


def stale_line(out_dir: Path, removed: dict[Path, str | None]) -> str:
    """What a run says of the earlier outputs it removed (``settle_earlier``): every file, and the steps that changed
    since they were written."""
    names = sorted(str(p.relative_to(out_dir)) for p in removed)
    steps = sorted({step for step in removed.values() if step})
    why = f"their step has changed since ({', '.join(steps)})" if steps else "the recipe has changed since"
    return f"removed {len(removed)} stale output(s) from {out_dir}, written by an earlier run: {why}: " + ", ".join(
        names
    )


def _current_key(recipe: Recipe) -> Callable[[str], str | None]:
    """The cache key a step (``node`` or ``node[variant]``) has in ``recipe`` now; None where it has no such step."""
    plan = Plan(recipe)

    def key(label: str) -> str | None:
        node, _, variant = label.partition("[")
        if node not in recipe.nodes:
            return None
        plan.add({node})
        return plan.keys.get(Instance(node, int(variant.rstrip("]")) if variant else None))

    return key


def _warn_others(out_dir: Path, files: list[Path], warn) -> None:
    """Say which files in ``out_dir`` neither the run nor an earlier one of its settings wrote (the manifest,
    recordings aside)."""
    kept = set(earlier_outputs(out_dir))  # the same settings' files, from an earlier run (``settle_earlier``)
    others = sorted(
        p.name
        for p in out_dir.iterdir()
        if p.is_file() and p not in files and p.name not in kept and p.name != MANIFEST and not p.name.endswith(".rrd")
    )
    if others and warn is not None:
        warn(
            f"{len(others)} other file(s) in {out_dir} are not from this run (see {MANIFEST}): "
            + ", ".join(others[:5])
            + (" …" if len(others) > 5 else "")
        )


def compute_in_pool(pool, recipe, wires, cache, plugins, reporter, max_seconds=None) -> dict[str, NodeRecord]:
    """Have ``pool`` (an ``pool.InstancePool``) compute every instance the outputs need that the cache
    lacks; their records by key."""
    if cache is None:
        raise NodegraphError("workers hand results over through the cache: a pool needs it (no --no-cache)")
    jobs = plan_jobs(recipe, wires, cache, RecipeRef.of(recipe, plugins), max_seconds)
    if not jobs:
        return {}
    results = pool.compute(jobs, cache.directory, reporter or Reporter(quiet=True))
    return {key: r.record for key, r in results.items() if r.record.status != "cached"}


def recording_id(recipe: Recipe) -> str:
    """The recording's id: the recipe's name and a digest of what it computes (overrides included), so a
    setting is always the same recording and two settings are two."""
    return f"{recipe.name}-{recipe.digest()[:16]}"


def recording_name(recipe: Recipe) -> str:
    """The recording's name in a viewer: the recipe and the overrides that make this setting."""
    return " ".join([recipe.name, *recipe.overrides])


def resolve_outputs(recipe: Recipe, refs: list[str]) -> list[Wire]:
    """``--output`` references: ``node.port`` or ``node`` (all its outputs)."""
    wires = []
    for ref in refs:
        node_id, _, port = ref.partition(".")
        entry = recipe.nodes.get(node_id)
        if entry is None:
            near = nearest(node_id, recipe.nodes)
            hint = f"; did you mean '{near}'?" if near else ""
            raise NodegraphError(
                f"--output {ref}: no node '{node_id}' in recipe {recipe.path}{hint}; "
                f"nodes: {', '.join(sorted(recipe.nodes))}"
            )
        if port and port not in entry.spec.outputs:
            near = nearest(port, entry.spec.outputs)
            hint = f"; did you mean '{node_id}.{near}'?" if near else ""
            raise NodegraphError(
                f"--output {ref}: node '{node_id}' has no output '{port}'{hint}; "
                f"outputs: {', '.join(entry.spec.outputs)}"
            )
        wires += [Wire(node_id, p) for p in ([port] if port else entry.spec.outputs)]
    return wires


__all__ = [
    "Executor",
    "RunResult",
    "compute_in_pool",
    "recording_id",
    "recording_name",
    "resolve_outputs",
    "run_recipe",
]
