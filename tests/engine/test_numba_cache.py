"""numba's cache keys each kernel on its own module and the project modules it imports: an edit recompiles
the kernels that can see it (and they compute the new result), no others."""

import json
import os
import subprocess
import sys
import textwrap

# Runs in a fresh process: compiles (or loads) the two kernels, counting compilations with the engine's
# own compile watch, and prints [compilations of apply, compilations of other, apply's result].
PROBE = """
import json
import numpy as np
import nodegraph, numba
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
    probe = "import nodegraph, os, numba; print(os.environ['NUMBA_CACHE_DIR']); print(numba.config.CACHE_DIR)"
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=True).stdout
    chosen, seen_by_numba = out.split()
    assert chosen == seen_by_numba == str(tmp_path / "nodegraph" / "numba")
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "mine")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=True).stdout
    assert out.split() == [str(tmp_path / "mine")] * 2
