"""numba's cache keys each kernel on its own module and the project modules it imports: an edit recompiles
the kernels that can see it (and they compute the new result), no others."""

import json
import os
import subprocess
import sys
import textwrap

import pytest

# Runs in a fresh process: compiles (or loads) the two kernels, counting compilations with the engine's
# own compile watch, and prints [compilations of apply, compilations of other, apply's result].
PROBE = """
import json
import numpy as np
import nodegraph, numba
from nodegraph import runtime
runtime.configure()
from nodegraph.compile_progress import CompileWatch

class Quiet:
    def info(self, text):
        pass

from kernels_pkg import other, user
with CompileWatch(Quiet(), "apply") as apply_watch:
    result = float(user.apply(np.ones(2))[0])
with CompileWatch(Quiet(), "other") as other_watch:
    other.other(np.ones(2))
print(json.dumps([apply_watch.kernels, other_watch.kernels, result]))
"""


def _kernel(body: str) -> str:
    return "import numba\n\n" + textwrap.dedent(body)


def test_an_edit_recompiles_only_the_kernels_that_import_it(tmp_path):
    package = tmp_path / "kernels_pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    helper = package / "helper.py"
    helper.write_text(_kernel("@numba.njit(cache=True)\ndef scale(x):\n    return 2.0 * x\n"))
    (package / "user.py").write_text(
        _kernel("from .helper import scale\n\n@numba.njit(cache=True)\ndef apply(x):\n    return scale(x) + 1.0\n")
    )
    (package / "other.py").write_text(_kernel("@numba.njit(cache=True)\ndef other(x):\n    return x - 1.0\n"))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_LOCATOR_CLASSES"}
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "numba")
    env["PYTHONPATH"] = os.pathsep.join([str(tmp_path), *sys.path])

    def run():
        done = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env, check=True)
        return json.loads(done.stdout.splitlines()[-1])

    assert run() == [1, 1, 3.0]  # empty cache: both compile
    assert run() == [0, 0, 3.0]  # both load from the cache
    helper.write_text(_kernel("@numba.njit(cache=True)\ndef scale(x):\n    return 5.0 * x\n"))
    assert run() == [1, 0, 6.0]  # the kernel inlining the helper recompiles, with the new helper; the other loads


def test_fresh_process_uses_the_project_directory_unless_the_user_sets_one(tmp_path):
    probe = (
        "import os, numba; from nodegraph import runtime; runtime.configure(); "
        "print(os.environ['NUMBA_CACHE_DIR']); print(numba.config.CACHE_DIR)"
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=True).stdout
    chosen, seen_by_numba = out.split()
    assert chosen == seen_by_numba == str(tmp_path / "nodegraph" / "numba")
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "mine")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=True).stdout
    assert out.split() == [str(tmp_path / "mine")] * 2


def _bare_env(tmp_path) -> dict:
    """This environment without numba's cache settings (conftest configured them), the user's cache in tmp_path."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "NUMBA_CACHE_LOCATOR_CLASSES")}
    env["XDG_CACHE_HOME"] = str(tmp_path / "user-cache")
    return env


def test_importing_the_engine_and_the_nodes_changes_no_environment_and_no_numba_setting(tmp_path):
    """``import nodegraph`` (and its modules, and the built-in nodes) sets nothing outside the package: numba's
    cache is configured by the entry points that run work (``runtime.configure``). Failed when ``import nodegraph``
    configured it."""
    probe = (
        "import json, os; before = dict(os.environ)\n"
        "import nodegraph, nodegraph.api, nodegraph.cli, nodegraph.executor, nodegraph.pool, nodes, numba\n"
        "print(json.dumps([dict(os.environ) == before, numba.config.CACHE_DIR, numba.config.CACHE_LOCATOR_CLASSES]))"
    )
    env = _bare_env(tmp_path)
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=True)
    assert json.loads(done.stdout.splitlines()[-1]) == [True, "", ""]


KERNEL_NODE = '''
import numpy as np

from nodegraph import Out, node
from nodegraph.values import Table
from toy_kernels import double  # decorated as the plugin loads, before any run starts


@node("kernel_toy", outputs={"table": Out(Table, "doubled")})
def kernel_toy(ctx):
    """Runs one numba kernel."""
    return Table({"x": double(np.arange(4.0))})
'''

TOY_RECIPE = "name: kernel_toy\nseed: 1\noutputs: [doubling.table]\nnodes:\n  doubling:\n    type: kernel_toy\n"

API_RUN = """
import sys
from nodegraph.api import default_registry, load_recipe, run_recipe
recipe = load_recipe("recipe.yaml", default_registry(plugins=["kernel_toy.py"]))
print(run_recipe(recipe).output("doubling.table").columns["x"].tolist())
"""


@pytest.mark.parametrize("entry", ["cli", "api"])
def test_a_run_caches_its_kernels_in_the_project_folder_under_the_module_digest(tmp_path, entry):
    """A run, from the command line or through the API, compiles its kernels into the user's numba folder
    (``$XDG_CACHE_HOME/nodegraph/numba``) with the per-module locator: each index is stamped with the module's
    code digest, not numba's (mtime, size) of the file. Also for a plugin that imports its kernel module (and so
    decorates the kernel) as it loads, before the run starts."""
    import pickle

    (tmp_path / "toy_kernels.py").write_text(_kernel("@numba.njit(cache=True)\ndef double(x):\n    return 2.0 * x\n"))
    (tmp_path / "kernel_toy.py").write_text(KERNEL_NODE)
    (tmp_path / "recipe.yaml").write_text(TOY_RECIPE)
    env = _bare_env(tmp_path)
    env["PYTHONPATH"] = os.pathsep.join([str(tmp_path), *sys.path])
    if entry == "cli":
        command = [sys.executable, "-m", "nodegraph.cli", "run", "recipe.yaml", "--plugin", "kernel_toy.py"]
        command += ["--no-cache", "--no-rrd", "--out-dir", str(tmp_path / "out")]
    else:
        command = [sys.executable, "-c", API_RUN]
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    indexes = list((tmp_path / "user-cache" / "nodegraph" / "numba").rglob("toy_kernels.double-*.nbi"))
    assert len(indexes) == 1, list((tmp_path / "user-cache").rglob("*"))
    assert not list(tmp_path.glob("__pycache__/*.nbi"))  # numba's own in-tree locator was not used
    with open(indexes[0], "rb") as handle:
        pickle.load(handle)  # numba's version
        stamp, _ = pickle.loads(handle.read())
    assert isinstance(stamp, str) and len(stamp) == 16  # code_digest.module_digest, not (mtime, size)
