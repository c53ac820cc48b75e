"""A first run compiles, in a second process, the numba kernels its later nodes will need while it computes the
earlier ones (issue 27: the main job's first run, empty numba cache, ≤ 90 s on 2 cores; docs/performance.md,
"Compiling ahead").

A first run compiles one kernel at a time on one core (numba compiles under a process-wide lock). When the run
starts, ``CompileAhead`` hands a worker process (``python -m nodegraph.compile_ahead``) the kernels recorded for
the node instances that will run (``kernel_signatures.json`` beside each node package: per node type and the
effects it receives, each kernel's module, name and argument types), latest node first. The worker compiles
them into the same on-disk numba cache; the run, meanwhile, computes and compiles from its first node on. When
the run reaches a node whose kernels the worker compiled, numba finds them in the cache (``Dispatcher.compile``
reads the cache index on each lookup) and loads the machine code. The two meet in the middle: the run tells
the worker which node it has reached, and the worker stops at nodes the run has passed.

Safe by construction: numba writes each cache file to a temporary name and renames it (``os.replace``), so a
reader sees a whole file or none; two processes compiling the same kernel write the same entry. A kernel with
more than one recorded signature is left to the run (two processes saving different signatures of one function
at once could pair an index entry with the other's data file). The worker prints nothing, stops when the run
closes its pipe and is killed if still running when the run ends; any failure in it (or in starting it) only
means the run compiles those kernels itself. It runs at the run's priority: its compiling is the run's own work
done earlier on the second core (as the run's parallel kernels and its preview use both), and at ``nice`` 10 on
a busy machine it compiled next to nothing (docs/performance.md).
A run that ends with every kernel of its worker's jobs in hand (compiled or loaded, so in numba's cache) marks
them cached (``CompileAhead.cached``): the next run with the same kernels, code and numba starts no worker, which
would only load them before the run does (1.6 CPU s of the main job's run from an empty node cache).
The worker starts only onto a free core (``core_free``: the load average leaves one idle besides the run's own;
``nodegraph/runtime.py``): on a busy machine it has no core of its own, only a share of the run's, and two
compilations side by side each ran slower (the main job's first run, ``--draft``, at load 8–12: 1.08× and 1.20×
the wall, 1.12× and 1.07× the CPU seconds with the worker, two pairs; docs/performance.md, "One policy for parallel
work").
``NODEGRAPH_COMPILE_AHEAD=off``: never; ``on``: whatever the load; unset (``auto``): onto a free core.

``python benchmarks/bench_compile.py --record`` rewrites the record from a first run of the main job.
"""

from __future__ import annotations

import base64
import importlib
import json
import os
import pickle
import subprocess
import sys
import threading
from collections.abc import Iterable
from dataclasses import asdict, dataclass
from functools import reduce
from pathlib import Path

RECORD = "kernel_signatures.json"
PLUGIN = "nodegraph_plugin_"  # registry.add_plugin_file's module names
ENV_VAR = "NODEGRAPH_COMPILE_AHEAD"


@dataclass(frozen=True)
class Job:
    """One kernel to compile: for the node at ``position`` in the run's order; ``args`` are numba's argument
    types, pickled (base64)."""

    position: int
    module: str
    name: str
    args: str
    plugin: str | None = None  # the file of a ``--plugin`` module (loaded under a name no finder knows)


def encode_types(args: tuple) -> str:
    """numba argument types as text for the record."""
    return base64.b64encode(pickle.dumps(tuple(args), protocol=4)).decode()


def decode_types(text: str) -> tuple:
    return pickle.loads(base64.b64decode(text))


def record_path(spec) -> Path | None:
    """The record of the package the node type ``spec`` comes from (its top-level package's folder)."""
    top = sys.modules.get((spec.module or spec.run.__module__).split(".")[0])
    where = getattr(top, "__file__", None)
    return None if where is None else Path(where).parent / RECORD


def _read(path: Path | None, seen: dict[Path, dict]) -> dict:
    if path is None:
        return {}
    if path not in seen:
        try:
            seen[path] = json.loads(path.read_text())
        except (OSError, ValueError):
            seen[path] = {}
    return seen[path]


def _loaded(module: str, name: str) -> bool:
    """Whether this process has kernel ``module.name`` compiled or loaded already (a run before this one in the
    same process, as ``nodegraph watch`` makes): nothing to compile ahead."""
    try:
        return bool(reduce(getattr, name.split("."), sys.modules[module]).signatures)
    except (KeyError, AttributeError):
        return False


def plan_jobs(recipe, order: Iterable, to_run: set, loaded_too: bool = False) -> list[Job]:
    """The kernels recorded for the instances in ``order`` that will run, each at the position of the first
    instance that needs it: per node type, the entry recorded for exactly the effects the node receives
    (``spec.effects & recipe.effects``; none recorded: nothing). Functions recorded with several signatures are
    left out (see the module's docstring); so are those this process has already, unless ``loaded_too``."""
    seen: dict[Path, dict] = {}
    jobs: dict[tuple[str, str, str], Job] = {}
    for position, inst in enumerate(order):
        if inst not in to_run:
            continue
        spec = recipe.nodes[inst.node].spec
        effects = sorted(spec.effects & recipe.effects)
        for entry in _read(record_path(spec), seen).get(spec.type_name, []):
            if entry.get("effects") != effects:
                continue
            for module, name, args in entry["kernels"]:
                if not loaded_too and _loaded(module, name):
                    continue
                plugin = getattr(sys.modules.get(module), "__file__", None) if module.startswith(PLUGIN) else None
                jobs.setdefault((module, name, args), Job(position, module, name, args, plugin))
    signatures: dict[tuple[str, str], int] = {}
    for module, name, _ in jobs:
        signatures[module, name] = signatures.get((module, name), 0) + 1
    return [job for (module, name, _), job in jobs.items() if signatures[module, name] == 1]


class CompileAhead:
    """The worker of one run: ``reached(position)`` as the run starts each instance, ``close()`` at its end."""

    command = [sys.executable, "-m", "nodegraph.compile_ahead"]

    def __init__(self, jobs: list[Job]):
        self.jobs = jobs
        self.process: subprocess.Popen | None = None

    @classmethod
    def start(cls, recipe, order: list, to_run: set) -> CompileAhead | None:
        """A started worker for the kernels ``to_run`` needs, or None (switched off, nothing recorded, or it
        could not start, or no core is free: the run compiles them itself)."""
        setting = os.environ.get(ENV_VAR, "auto").lower()
        if setting in ("off", "0", "false", "no"):
            return None
        if setting == "auto" and not core_free():
            return None
        try:
            ahead = cls(plan_jobs(recipe, order, to_run))
            if not ahead.jobs or ahead.cached():
                return None
            ahead.spawn()
            return ahead
        except Exception:
            return None

    def marker(self) -> Path | None:
        """The file that says the kernels of ``jobs`` are all in numba's cache, named by what their entries there
        depend on: each kernel and its argument types, the digest of its module's code (the entry's stamp,
        ``numba_locator``), numba's and Python's versions, the CPU compiled for; inside the cache folder, so that
        clearing it clears this too. None where a module has no source file."""
        import hashlib
        from importlib.metadata import version

        from . import numba_cache, runtime
        from .code_digest import module_digest
        from .node_packages import project_packages

        runtime.configure()
        packages = project_packages()
        rows = []
        for job in sorted(self.jobs, key=lambda job: (job.module, job.name, job.args)):
            digest = module_digest(job.module, packages)
            if not digest:
                return None
            rows.append([job.module, job.name, job.args, digest])
        cpu = os.environ.get("NUMBA_CPU_NAME", "")  # entries are keyed on the CPU compiled for (numba_cache)
        key = json.dumps([rows, version("numba"), sys.version, cpu], separators=(",", ":"))
        name = hashlib.sha256(key.encode()).hexdigest()[:32]
        return Path(os.environ[numba_cache.ENV_VAR]) / "compile_ahead" / f"{name}.cached"

    def mark(self) -> None:
        """Where this process has every kernel of ``jobs`` (compiled or loaded: numba's cache has them), say so for
        the next run (``cached``)."""
        try:
            if all(_loaded(job.module, job.name) for job in self.jobs):
                marker = self.marker()
                if marker is not None:
                    marker.parent.mkdir(parents=True, exist_ok=True)
                    marker.touch()
        except Exception:  # a read-only cache folder, a module that went: said as due next time, nothing else lost
            pass

    def cached(self) -> bool:
        """Whether an earlier run left every kernel of ``jobs`` in numba's cache (``close``): a worker would only
        load them (1.6 CPU s of the main job's run, beside it on the second core) before the run loads them too."""
        marker = self.marker()
        return marker is not None and marker.is_file()

    def spawn(self) -> None:
        from . import runtime

        runtime.configure()  # the worker compiles into the run's cache, with the run's locator
        self.process = subprocess.Popen(
            self.command,
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        self._send(json.dumps([asdict(job) for job in self.jobs]))

    def _send(self, line: str) -> None:
        if self.process is None or self.process.poll() is not None:
            return
        try:
            self.process.stdin.write(line + "\n")
            self.process.stdin.flush()
        except (OSError, ValueError):  # the worker is gone: the run compiles what is left
            pass

    def reached(self, position: int) -> None:
        """The run starts the instance at ``position``: the worker compiles nothing for earlier ones."""
        self._send(str(position))

    def close(self) -> None:
        """The run is over: the worker stops (killed if it does not within a moment). When this process has every
        kernel of ``jobs`` (compiled or loaded: numba's cache has them), the next run with the same kernels starts
        no worker (``cached``)."""
        process, self.process = self.process, None
        if process is None:
            return
        self.mark()
        try:
            process.stdin.close()
        except OSError:
            pass
        try:
            process.wait(timeout=0.5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


class _Node:
    """A node of a recipe as ``plan_jobs`` reads an instance: by its id."""

    def __init__(self, node: str):
        self.node = node


def _every_job(recipe) -> list[Job]:
    """The kernels recorded for every node of ``recipe``, whether or not this process has them."""
    nodes = [_Node(node) for node in recipe.nodes]
    return plan_jobs(recipe, nodes, set(nodes), loaded_too=True)


def kernels_due(recipe) -> bool:
    """Whether a run of ``recipe`` may have kernels to compile: not once a run of it has ended with every kernel
    recorded for its nodes in numba's cache (``mark_compiled``: a clean clone's first run, or one after a change to
    a kernel's code, compiles; later runs load them), nor where none is recorded. What ``check`` and ``run`` say
    beside their estimate of the time."""
    try:
        jobs = _every_job(recipe)
        if not jobs or CompileAhead(jobs).cached():
            return False
        return not _shipped({job.module for job in jobs if job.plugin is None}, any(job.plugin for job in jobs))
    except Exception:  # a record or a module that cannot be read: as if they were due
        return True


def _shipped(modules: set[str], plugins: bool) -> bool:
    """Whether the kernel bundle kept in git holds the current kernels of every module of ``modules`` (and no
    ``--plugin`` kernel is due): a clean clone's first run then loads them and compiles none (it had said "its kernels
    are not compiled yet" to a new user whose run compiled nothing)."""
    from . import kernel_bundle

    bundle = kernel_bundle.bundle_path()
    return not plugins and bundle is not None and modules <= kernel_bundle.current_modules(bundle)


def mark_compiled(recipe) -> None:
    """At the end of a run: where this process has every kernel recorded for the recipe's nodes, mark them so
    (``CompileAhead.mark``), whether or not a worker compiled ahead."""
    try:
        jobs = _every_job(recipe)
    except Exception:  # a record that cannot be read: said as due next time
        return
    if jobs:
        CompileAhead(jobs).mark()


def core_free() -> bool:
    """Whether a core is idle besides the one this run uses: the 1-minute load average plus one is at most the
    cores this process may run on (no load average: assumed free)."""
    try:
        load = os.getloadavg()[0]
    except OSError:
        return True
    return load + 1.0 <= len(os.sched_getaffinity(0))


def latest_first(jobs: list[Job]) -> list[Job]:
    """The worker's order: the last node's kernels first and, within a node, its last kernel first, so that the
    run (first to last) and the worker meet in the middle."""
    return list(reversed(sorted(jobs, key=lambda job: job.position)))


def work(jobs: list[Job], reached: list[int]) -> list[str]:
    """Compile ``jobs`` latest first, stopping at the first whose node the run has passed (``reached[0]``);
    kernels cached already are only loaded (numba's public ``stats`` tell the two apart). Returns the kernels
    compiled (``module.name``)."""
    compiled = []
    for job in latest_first(jobs):
        if job.position < reached[0]:
            break
        try:
            if job.plugin is not None and job.module not in sys.modules:
                from .registry import Registry

                Registry().add_plugin_file(job.plugin)  # as the run loaded it: same module name, same digest
            dispatcher = reduce(getattr, job.name.split("."), importlib.import_module(job.module))
            sig = decode_types(job.args)
            misses = sum(dispatcher.stats.cache_misses.values())
            dispatcher.compile(sig)  # from numba's cache where it is there already
            if sum(dispatcher.stats.cache_misses.values()) > misses:
                compiled.append(f"{job.module}.{job.name}")
        except Exception:  # a stale record, a kernel that does not compile: the run compiles (and reports) it
            continue
    return compiled


def main() -> None:
    jobs = [Job(**job) for job in json.loads(sys.stdin.readline())]
    reached = [-1]

    def follow() -> None:
        for line in sys.stdin:
            reached[0] = max(reached[0], int(line))
        reached[0] = sys.maxsize  # the run closed the pipe (it ended, or died): stop at the next kernel

    threading.Thread(target=follow, daemon=True).start()
    from . import runtime

    runtime.configure()
    work(jobs, reached)


if __name__ == "__main__":
    main()
