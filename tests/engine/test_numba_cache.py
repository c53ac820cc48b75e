"""numba's cache directory follows the node packages' source, so no kernel runs stale inlined code."""

import os
import subprocess
import sys

from nodegraph import numba_cache


def test_digest_changes_with_any_source_file(tmp_path, monkeypatch):
    package = tmp_path / "kernels_pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "helper.py").write_text("def f(x):\n    return x + 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    first = numba_cache.source_digest("kernels_pkg")
    assert first == numba_cache.source_digest("kernels_pkg")
    (package / "helper.py").write_text("def f(x):\n    return x + 2\n")
    assert numba_cache.source_digest("kernels_pkg") != first


def test_fresh_process_uses_a_source_keyed_directory_unless_the_user_sets_one(tmp_path):
    probe = "import nodegraph, os, numba; print(os.environ['NUMBA_CACHE_DIR']); print(numba.config.CACHE_DIR)"
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=True).stdout
    chosen, seen_by_numba = out.split()
    assert chosen == seen_by_numba
    assert chosen == str(tmp_path / "nodegraph" / "numba" / numba_cache.source_digest("nodes"))
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "mine")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, check=True).stdout
    assert out.split() == [str(tmp_path / "mine")] * 2
