"""A node whose numba kernel compiles says so (a first run can spend a minute compiling); with the
kernel in numba's cache, the run prints nothing about compiling."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

KERNELS = """
import numpy as np
from numba import njit


@njit(cache=True)
def double(values):
    out = np.empty_like(values)
    for i in range(values.size):
        out[i] = 2.0 * values[i]
    return out
"""

PLUGIN = '''
import numpy as np

from nodegraph import Out, node
from nodegraph.values import Table
{eager}

@node("kernel_toy", outputs={{"table": Out(Table, "doubled")}})
def kernel_toy(ctx):
    """Runs one numba kernel."""
    {lazy}
    return Table({{"x": double(np.arange(4.0))}})
'''

IMPORT = "from toy_kernels import double"

RECIPE = """\
name: kernel_toy
seed: 1
outputs: [doubling.table]
nodes:
  doubling:
    type: kernel_toy
"""


def _run(tmp_path: Path) -> str:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    command = [sys.executable, "-m", "nodegraph.cli", "run", str(tmp_path / "recipe.yaml"), "--plugin"]
    command += [str(tmp_path / "kernel_toy.py"), "--no-cache", "--no-rrd", "--out-dir", str(tmp_path / "out")]
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    return done.stderr


@pytest.mark.parametrize("lazy", [False, True], ids=["numba-loaded-before-the-node", "numba-loaded-by-the-node"])
def test_compiling_is_announced_once_then_cached(tmp_path, lazy):
    """Also when the node imports its kernel module (and with it numba) only as it runs, as the project's nodes
    do: that compile was silent while the watch listened only when numba had loaded before the node started."""
    plugin = PLUGIN.format(eager="" if lazy else IMPORT, lazy=IMPORT if lazy else "")
    (tmp_path / "kernel_toy.py").write_text(plugin)
    (tmp_path / "toy_kernels.py").write_text(KERNELS)
    (tmp_path / "recipe.yaml").write_text(RECIPE)
    first = _run(tmp_path)
    # issue 47: a first run said "first run after a code change" to someone who had changed nothing
    assert "compiling kernels for doubling (not in numba's cache yet: compiled once, cached afterwards)" in first
    assert "doubling: compiling toy_kernels.double (kernel 1)…" in first  # which kernel, as it starts
    assert "compiled 1 kernel(s) for doubling in " in first
    again = [line for line in _run(tmp_path).splitlines() if not line.startswith("outputs go to")]
    assert not [line for line in again if "compil" in line]  # (the output folder's path names the test)
    (tmp_path / "toy_kernels.py").write_text(KERNELS + "\n# edited\n")
    assert "compiling kernels for doubling (their code changed since they were cached" in _run(tmp_path)
