"""Benchmarks leave the interpreter and the committed files alone: none edits ``sys.path`` (``bench_contact``
put its own folder first to import ``bench_scenes``), a ``--quick`` run writes nothing into docs/ (``bench_skin``
rewrote the committed ``docs/images/skin_sweep.png``), and ``bench_contact --quick`` runs on a clean clone, which
has no ``../shared/tools`` checkers beside it (it stopped at its arguments)."""

import ast
import importlib.util
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


def load(name: str, monkeypatch):
    spec = importlib.util.spec_from_file_location(f"benchmark_{name}", BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, module)
    spec.loader.exec_module(module)
    return module


def test_no_benchmark_edits_sys_path():
    edits = []
    for path in sorted(BENCHMARKS.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            target = node.func.value if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) else None
            if target is not None and ast.unparse(target) == "sys.path":
                edits.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
            if isinstance(node, ast.Assign | ast.AugAssign):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                edits += [f"{path.name}:{node.lineno}" for t in targets if ast.unparse(t).startswith("sys.path")]
    assert not edits, "benchmarks that edit sys.path:\n" + "\n".join(edits)


def test_a_quick_skin_run_writes_nothing_into_docs(tmp_path, monkeypatch):
    """Run by hand (no $NODEGRAPH_BENCH_RESULTS), ``bench_skin --quick`` wrote its picture over the committed one."""
    bench = load("bench_skin", monkeypatch)
    monkeypatch.delenv("NODEGRAPH_BENCH_RESULTS", raising=False)
    monkeypatch.setattr(bench, "ROOT", tmp_path)  # a checkout of its own: docs/ and benchmarks/results/ in tmp_path
    monkeypatch.setattr(bench, "library_scores", lambda *args: ([0.05], {"variety": "japonica"}))
    grains = [(blur, sink, None, 0.05) for blur in bench.BLURS for sink in bench.SINKS]
    monkeypatch.setattr(bench, "sweep_grains", lambda: grains)
    pictures = []
    monkeypatch.setattr(bench, "render_sweep", lambda grains, path: pictures.append(path))
    bench.main(["--quick"])
    assert pictures and not pictures[0].is_relative_to(tmp_path / "docs"), pictures
    assert not (tmp_path / "docs").exists()


def test_a_quick_contact_run_needs_no_checkers(tmp_path, monkeypatch, capsys):
    """Without ``../shared/tools`` (a clean clone) or ``$NODEGRAPH_CHECKERS``, ``--quick`` skips the checkers and
    says so; a full run stops and says where to point."""
    bench = load("bench_contact", monkeypatch)
    monkeypatch.delenv("NODEGRAPH_CHECKERS", raising=False)
    monkeypatch.setattr(bench, "REPO", tmp_path / "clone")  # nothing beside it
    given = []
    monkeypatch.setattr(bench, "measure", lambda name, variant, full, checkers, work: given.append(checkers) or {})
    assert bench.main(["--quick"]) == 0
    assert given == [None]  # the recipe's own contact step only
    assert "checkers skipped" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        bench.main(["ikura_don"])
    assert "NODEGRAPH_CHECKERS" in capsys.readouterr().err
    monkeypatch.setenv("NODEGRAPH_CHECKERS", str(tmp_path))
    (tmp_path / "overlap_check.py").write_text("")
    (tmp_path / "mesh_quality.py").write_text("")
    given.clear()
    assert bench.main(["--quick"]) == 0 and given == [tmp_path]
