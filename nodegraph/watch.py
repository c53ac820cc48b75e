"""What ``nodegraph watch`` keeps between runs, and how it stops a step a save made unneeded.

Between saves it also warms up: the first run of a node in a process pays for its imports, the kernels numba
loads from its cache and what the node derives from its inputs (``codec.derived``), which an edit would
otherwise pay on top of the node's own work (4 s against 1 s for the main job's shading). So once a run is
done, the watch loads the inputs of the quick nodes it has not run yet and runs each once more on them
(``Executor.rehearse``), one step at a time, looking at the file between steps.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Iterator

from . import interrupt
from .cache import Cache
from .executor import Executor, RunResult
from .plan import Instance

REHEARSE_S = 2.0  # a node that took longer when it ran is not rehearsed: there a first load is a small part


def run_name(run: int) -> str:
    """How the watch names its ``run``-th run: the first is the watch's start, each later one a save's."""
    return "first run" if run == 1 else f"run {run}"


class Superseded(KeyboardInterrupt):
    """A watched run stopped because the recipe was saved again and the step it was at is no longer needed."""


class WatchSession:
    """What ``nodegraph watch`` keeps between runs: the last run's values by cache key (an edit re-runs a
    node from its inputs in memory, not from the cache), and when the current run began, to say when each
    node that ran reached the recording (and a viewer streaming it).

    A save during a run does not wait for it: ``supersede`` gets the cache keys the saved recipe needs, and
    a step that is not among them stops at once (a signal: a path-traced preview stops within its render, a
    Python loop at its next line) or before it starts; a step the new recipe still needs (a long
    simulation under a shading edit) runs on, and the next run takes its result from memory.

    Between saves, ``warm_up`` readies the quick nodes the runs so far took from the cache; a save stops it
    the same way (``stop_warm_up``)."""

    def __init__(self):
        self.kept: dict = {}
        self.run = 0
        self.seen = time.perf_counter()
        self.lock = threading.Lock()
        self.running = None  # (instance, key) of the step computing now
        self.needed: set[str] | None = None  # the keys the file's last save needs; None: unchanged, or a bad edit
        self.stopping: str | None = None  # the key of the step a signal was sent to stop
        self.warm: set[str] = set()  # keys of the instances run (or rehearsed) in this process
        self.last: RunResult | None = None  # the last run that completed
        self.warm_stopped = False  # a save came during the warm-up

    def begin(self, run: int, seen: float) -> None:
        self.run, self.seen = run, seen
        self.running, self.needed, self.stopping = None, None, None

    def _stop_running(self) -> None:
        """Under ``lock``: signal the main thread to stop the step running now (see ``interrupted``)."""
        self.stopping = self.running[1]
        # to the main thread, which runs the step: Mitsuba's own SIGINT handler cancels the render it runs
        if hasattr(signal, "pthread_kill"):
            signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)
        else:  # no POSIX threads' signals (Windows): Python code stops, a render runs to its end
            import _thread

            _thread.interrupt_main()

    def started(self, inst, key) -> None:
        """Before a step runs: stop the run here if the last save no longer needs this step."""
        with self.lock:
            if self.needed is not None and key not in self.needed:
                raise Superseded(inst.label)
            self.running = (inst, key)
            self.warm.add(key)

    def ran(self, inst) -> None:
        with self.lock:
            self.running = None
        seconds = time.perf_counter() - self.seen
        first = self.run == 1  # no save yet: the watch's own first run
        done, since = ("ready", "the watch started") if first else ("updated", "the save was seen")
        print(f"{run_name(self.run)}: {inst.label} {done} {seconds:.2f} s after {since}", flush=True)

    def supersede(self, needed: set[str] | None) -> None:
        """The file was saved (again) during the run; ``needed``: the keys it now needs (None: a bad edit,
        the run goes on and the error shows after it). Stop the step computing now if it is not needed."""
        with self.lock:
            self.needed = needed
            if needed is not None and self.running is not None and self.running[1] not in needed:
                self._stop_running()

    def stop_warm_up(self) -> None:
        """The file was saved during ``warm_up``: stop the step rehearsing now, and the steps after it."""
        with self.lock:
            self.warm_stopped = True
            if self.running is not None:
                self._stop_running()

    def interrupted(self, signum, frame) -> None:
        """SIGINT: Ctrl-C, or ``supersede`` stopping a step (then raised only while that step still runs;
        once it has finished, the next step's start stops the run)."""
        stopping, running = self.stopping, self.running
        if stopping is None:
            if interrupt.repeated():  # the same Ctrl-C, passed on by the supervising parent
                return
            raise KeyboardInterrupt
        self.stopping = None
        if running is not None and running[1] == stopping:
            raise Superseded(running[0].label)

    def keep(self, result: RunResult) -> None:
        """Hold only what the last run used; remember the run for ``warm_up``."""
        keys = set(result.keys.values())
        self.kept = {key: self.kept[key] for key in keys if key in self.kept}
        self.last = result

    def warm_up(self, cache: Cache) -> Iterator[str]:
        """Steps (one per ``next``, each yielding the instance's label) that ready the last run's nodes for an
        edit: each instance not yet run in this process, whose inputs are cached and whose run took at most
        ``REHEARSE_S`` when it ran (``Cache.recorded_seconds``), gets its inputs loaded into ``kept`` and is
        rehearsed. The instances whose edit re-runs the least come first (its own and its dependants' recorded
        seconds): there a first load weighs most. The caller looks for a save between steps."""
        if self.last is None:
            return
        executor = Executor(self.last.recipe, cache, session=self)
        # a rehearsal only loads: an input whose entry went since (evicted, cleared, torn) is not computed
        # here, where it could take minutes, print as a run and outlast a save; its step is skipped
        executor.on_start, executor.on_ran = _refuse_to_compute, None
        order = executor.plan({inst.node for inst in self.last.keys})
        keys = executor.keys
        executor.hits = {key for key in set(keys.values()) if cache.has(key)}
        # a node never cached (``NodeSpec.store``) has no entry to say how long it took: its last run says
        ran = {record.node: record.seconds for record in self.last.records if record.status == "ran"}
        seconds = {
            inst: cache.recorded_seconds(keys[inst])
            if self.last.recipe.nodes[inst.node].spec.store
            else ran.get(inst.label)
            for inst in order
        }
        planned = executor.planned
        sources = {inst: {src for pairs in planned.sources(inst).values() for src, _ in pairs} for inst in order}
        dependants: dict[Instance, set[Instance]] = {inst: set() for inst in order}
        for inst in reversed(order):  # reverse topological: each instance's dependants are complete before its own
            for src in sources[inst]:
                dependants[src] |= {inst} | dependants[inst]

        def edit_seconds(inst: Instance) -> float:
            return sum(REHEARSE_S if seconds[i] is None else seconds[i] for i in {inst} | dependants[inst])

        ready = [
            inst
            for inst in order
            if keys[inst] not in self.warm
            and seconds[inst] is not None
            and seconds[inst] <= REHEARSE_S
            and all(keys[src] in self.kept or keys[src] in executor.hits for src in sources[inst])
        ]
        for inst in sorted(ready, key=edit_seconds):
            if keys[inst] in self.warm:  # an identical instance elsewhere in the recipe was rehearsed
                continue
            with self.lock:
                if self.warm_stopped:
                    return
                self.running = (inst, keys[inst])
            try:
                executor.rehearse(inst)
            except Exception:  # an input not in hand (``_refuse_to_compute``), or the node failed where its run
                pass  # had not: the edit computes it, and shows a failure at its place
            finally:
                with self.lock:  # a stop signalled as the step ended is dropped by ``interrupted``
                    self.running = None
            self.warm.add(keys[inst])
            yield inst.label


class _NotInHand(Exception):
    """A rehearsal's input is neither held nor cached: computing it is the next run's job."""


def _refuse_to_compute(inst: Instance, key: str) -> None:
    raise _NotInHand(inst.label)
