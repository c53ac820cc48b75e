"""Fixtures shared by several test folders: a small synthetic aggregate (capsule grains + ikura eggs with
membrane/yolk parts, a bowl) and that aggregate shaded, for the shading and the export tests."""

import os
import tempfile
from pathlib import Path

import pytest

from nodegraph import kernel_bundle, runtime

# the suite remembers code digests in a file of its own, not in the user's cache (``nodegraph.code_digest``);
# processes it starts inherit the choice
os.environ.setdefault("NODEGRAPH_CODE_DIGESTS", os.path.join(tempfile.mkdtemp(prefix="nodegraph-digests-"), "d.json"))
# processes the tests start unpack no bundle into caches of their own: a test of compiling starts from an empty cache
# (a test of the bundle names its own)
os.environ.setdefault("NODEGRAPH_KERNEL_BUNDLE", "off")
# numba's kernel cache and per-module locator, as a run has them (``import nodegraph`` sets nothing), before a test
# imports a kernel module; processes the tests start inherit them
runtime.configure()
# the suite's own cache starts from the shipped kernels, as a user's first run does (``kernel_bundle``): numba loads
# an entry only where its module's code digest and the kernel's bytecode are the code under test, so a changed kernel
# compiles from source (and ``test_kernel_bundle`` fails on a stale bundle). On a clean clone the suite took 1,149 CPU s
# compiling every kernel, 912 with the bundle (benchmarks/measured/test_suite.jsonl)
kernel_bundle.install(kernel_bundle.BUNDLE, Path(os.environ["NUMBA_CACHE_DIR"]))


@pytest.fixture(scope="session")
def scene_inputs():
    from scene_builders import small_food_scene

    return small_food_scene()


@pytest.fixture(scope="session")
def shaded(scene_inputs):
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade

    return shade.call(**scene_inputs, material=cooked_material())


def pytest_configure(config):
    # NODEGRAPH_TEST_CPU_LOG=FILE: one JSON line per test with its CPU seconds (this process and its finished
    # children, setup to teardown): where the suite's time goes, independent of the machine's load
    path = os.environ.get("NODEGRAPH_TEST_CPU_LOG")
    if path:
        config.pluginmanager.register(CpuLog(path), "nodegraph-cpu-log")


class CpuLog:
    def __init__(self, path):
        self.path = path

    @staticmethod
    def _cpu():
        import resource

        own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item, nextitem):
        import json
        import time

        cpu, wall = self._cpu(), time.perf_counter()
        yield
        with open(self.path, "a") as log:
            record = {"test": item.nodeid, "cpu_s": self._cpu() - cpu, "wall_s": time.perf_counter() - wall}
            log.write(json.dumps(record) + "\n")
