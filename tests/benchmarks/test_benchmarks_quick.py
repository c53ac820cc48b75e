"""Every benchmark runs in its ``--quick`` mode (seconds each), so none can rot unnoticed (one did: it failed
at import for weeks because nothing ran it). Found by glob: a benchmark added to ``benchmarks/`` is covered.

A benchmark that needs packages outside the project's dependencies names them in a module-level
``REQUIRES = ("pkg", ...)`` and is skipped where they are missing. Results go to a temporary folder
(``NODEGRAPH_BENCH_RESULTS``), not to ``benchmarks/results/``, and nothing goes into docs/. Marked
``bench_quick``: CI runs them with the rest (``-m "not bench_quick"`` leaves them out).
"""

import ast
import importlib.util
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BENCHMARKS = sorted((ROOT / "benchmarks").glob("bench_*.py"))
CPU_LIMIT_S = 180  # one benchmark's --quick run in CPU seconds, compile of its kernels included (cold numba cache)
HANG_S = 900  # wall-clock guard only: on the shared 2-core machine at load 15 a 25 CPU-second run took 256 s


def children_cpu() -> float:
    """CPU seconds (user + system) of this process's finished children: the work, whatever the machine's load."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def docs_stamps() -> dict[Path, tuple[int, int]]:
    """Size and modification time of every file under docs/: a ``--quick`` run changes none."""
    return {p: (p.stat().st_size, p.stat().st_mtime_ns) for p in (ROOT / "docs").rglob("*") if p.is_file()}


def module_constant(path: Path, name: str, default):
    """A benchmark's module-level ``name = <literal>``, or ``default``."""
    for statement in ast.parse(path.read_text()).body:
        if isinstance(statement, ast.Assign) and any(getattr(t, "id", None) == name for t in statement.targets):
            return ast.literal_eval(statement.value)
    return default


def requires(path: Path) -> tuple[str, ...]:
    return tuple(module_constant(path, "REQUIRES", ()))


@pytest.mark.bench_quick
@pytest.mark.parametrize("path", BENCHMARKS, ids=[p.stem for p in BENCHMARKS])
def test_benchmark_quick_mode_runs(path, tmp_path, monkeypatch):
    assert "--quick" in path.read_text(), f"{path.name} needs a --quick mode (seconds) for CI"
    missing = [name for name in requires(path) if importlib.util.find_spec(name) is None]
    if missing:
        pytest.skip(f"needs {', '.join(missing)} (REQUIRES)")
    env = dict(
        os.environ,
        NODEGRAPH_BENCH_RESULTS=str(tmp_path),
        MPLBACKEND="Agg",
        PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])),
    )
    docs = docs_stamps()
    start, cpu_start = time.perf_counter(), children_cpu()
    done = subprocess.run(
        [sys.executable, str(path), "--quick"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=HANG_S,
    )
    seconds, cpu = time.perf_counter() - start, children_cpu() - cpu_start
    assert done.returncode == 0, f"{path.name} --quick failed:\n{done.stdout[-2000:]}\n{done.stderr[-4000:]}"
    changed = sorted({str(p.relative_to(ROOT)) for p, _ in docs_stamps().items() ^ docs.items()})
    assert not changed, f"{path.name} --quick wrote into docs/ (results go to $NODEGRAPH_BENCH_RESULTS): {changed}"
    print(f"{path.name} --quick: {seconds:.1f} s wall, {cpu:.1f} CPU s (load {os.getloadavg()[0]:.1f})")
    # a benchmark whose smoke run is a whole recipe states its own budget (``QUICK_CPU_S``), compile included
    limit = module_constant(path, "QUICK_CPU_S", CPU_LIMIT_S)
    assert cpu <= limit, f"{path.name} --quick used {cpu:.0f} CPU s (budget {limit}): a smoke run must take seconds"
    report_sections_read(path.stem, done.stdout, tmp_path, monkeypatch)


def report_sections_read(stem, stdout, results, monkeypatch):
    """docs/accuracy.md's sections for this benchmark are made from its output: each finds its table and
    the knob's default row in it (so a changed table format or a default left out of the grid fails here,
    not when the report is next regenerated)."""
    spec = importlib.util.spec_from_file_location("accuracy_report", ROOT / "benchmarks" / "accuracy_report.py")
    report = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(report)
    monkeypatch.setattr(report, "IMAGES", results / "images")
    defaults = report.defaults()
    for make in report.SECTIONS.get(stem, ()):
        lines = make(stdout, defaults, results, True)
        text = "\n".join(lines)
        assert lines[0].startswith("## ") and "**Default" in text, f"{make.__name__}: no default stated"
        assert any(line.startswith("| **") for line in text.splitlines()), f"{make.__name__}: no default row in bold"
