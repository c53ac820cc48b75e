"""Without the optional peer extra, the XPBD-against-Newton benchmark says what to install and exits 2
instead of stopping with a traceback."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "bench_xpbd_newton.py"


def test_missing_peer_names_the_extra_and_exits_2(tmp_path):
    hide = (  # a None entry in sys.modules makes the package look absent, installed or not
        "import runpy, sys; sys.modules['newton'] = None; "
        f"sys.argv = [{str(SCRIPT)!r}, '--quick']; runpy.run_path({str(SCRIPT)!r}, run_name='__main__')"
    )
    path = os.pathsep.join(filter(None, [str(ROOT / "benchmarks"), str(ROOT), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, PYTHONPATH=path, NODEGRAPH_BENCH_RESULTS=str(tmp_path))
    done = subprocess.run([sys.executable, "-c", hide], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert 'pip install -e ".[peer]"' in done.stderr and "newton" in done.stderr
    assert "Traceback" not in done.stderr
