"""Tells the user when a node's numba kernels compile (a first run, or one after a code change, can spend a minute
there, silent otherwise), why, and how long it took; cached kernels load without a compile event, so a warm
run prints nothing."""

from __future__ import annotations

import importlib.abc
import importlib.util
import os
import sys
import time

from .report import Reporter


class CompileWatch:
    """Listens to numba's ``numba:compile`` events while one node runs.

    A line goes out at the first compilation, one naming each kernel as its compilation starts (one can take
    half a minute), and at the end the seconds spent compiling (outermost compilations only: a kernel compiles
    the helpers it calls inside its own event).
    """

    def __init__(self, reporter: Reporter, node: str):
        self.reporter = reporter
        self.node = node
        self.kernels = 0
        self.seconds = 0.0
        self._depth = 0
        self._started = 0.0
        self._listener = None
        self._hook = None

    def __enter__(self) -> CompileWatch:
        if "numba" not in sys.modules:  # numba loads lazily, with the node's kernels: listen once it has loaded
            self._hook = _AfterImport("numba", self._listen)
            sys.meta_path.insert(0, self._hook)
            return self
        self._listen()
        return self

    def _listen(self) -> None:
        from numba.core import event

        watch = self

        class _Listener(event.Listener):
            def on_start(self, ev) -> None:
                dispatcher = ev.data.get("dispatcher")
                watch.compile_started(_kernel_name(dispatcher), _why_compiling(dispatcher))

            def on_end(self, ev) -> None:
                watch.compile_ended()

        self._listener = _Listener()
        event.register("numba:compile", self._listener)

    def compile_started(self, kernel: str = "a kernel", why: str = "compiled once, cached afterwards") -> None:
        if self._depth == 0:
            if self.kernels == 0:
                self.reporter.info(f"compiling kernels for {self.node} ({why})…")
            self.kernels += 1
            elapsed = f", {self.seconds:.0f} s so far" if self.kernels > 1 else ""
            self.reporter.info(f"  {self.node}: compiling {kernel} (kernel {self.kernels}{elapsed})…")
            self._started = time.perf_counter()
        self._depth += 1

    def compile_ended(self) -> None:
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._started

    def __exit__(self, *exc) -> None:
        if self._hook in sys.meta_path:
            sys.meta_path.remove(self._hook)
        if self._listener is None:
            return
        from numba.core import event

        event.unregister("numba:compile", self._listener)
        if self.kernels:
            self.reporter.info(f"compiled {self.kernels} kernel(s) for {self.node} in {self.seconds:.1f} s")


def _why_compiling(dispatcher) -> str:
    """Why a kernel compiles, from numba's cache index of it: none yet (a first run on this machine, or after the
    cache was cleared), one for other code (its module or one it imports changed: the stamp, ``numba_locator``), or
    one for this code but other argument types."""
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    index = getattr(cache_file, "_index_path", None)
    if index is None:  # not a cached kernel (cache=False): it compiles in every process
        return "compiled in every run"
    try:
        if not os.path.exists(index):
            return "not in numba's cache yet: compiled once, cached afterwards"
        if not cache_file._load_index():
            return "their code changed since they were cached; cached afterwards"
    except Exception:  # numba's internals moved: say what is true either way
        return "compiled once, cached afterwards"
    return "new argument types; cached afterwards"


def _kernel_name(dispatcher) -> str:
    """``module.function`` of the kernel a compile event is for."""
    func = getattr(dispatcher, "py_func", None)
    return f"{func.__module__}.{func.__qualname__}" if func is not None else "a kernel"


class _AfterImport(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """A one-shot import hook: lets module ``name`` load as usual, then calls ``then`` (numba's event registry
    exists only once numba has loaded, and loading it for every node would cost a second of each run)."""

    def __init__(self, name: str, then):
        self.name = name
        self.then = then
        self._loader = None

    def find_spec(self, fullname, path, target=None):
        if fullname != self.name:
            return None
        sys.meta_path.remove(self)  # one shot; also lets the lookup below find the real module
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None:
            return spec
        self._loader, spec.loader = spec.loader, self
        return spec

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module) -> None:
        self._loader.exec_module(module)
        self.then()
