"""A node declared ``store=False`` (outputs cheaper to compute again than to store: a scene description, files'
bytes) never goes into the cache, whose limit it filled (issue 47); a run computes it where it is needed, and a
cached re-run with current files still writes nothing."""

import json

from nodegraph.cli import main

PLUGIN = '''
import numpy as np

from nodegraph import In, Out, Param, node
from nodegraph.values import Table


@node("toy_big", outputs={"table": Out(Table, "rows")}, params={"n": Param(int, 4, "n", range=(1, 9))}, store=False)
def toy_big(ctx, *, n):
    """Large and quick: never cached."""
    return Table({"x": np.arange(n, dtype=float)})


@node("toy_total", inputs={"table": In(Table, "rows")}, outputs={"table": Out(Table, "their sum")})
def toy_total(ctx, table):
    """Sums a column: cached as usual."""
    return Table({"sum": np.array([table.columns["x"].sum()])})
'''

RECIPE = """\
name: stored
outputs: [big, total]
nodes:
  big: {type: toy_big}
  total: {type: toy_total, inputs: {table: big.table}}
"""


def cached_nodes(cache):
    return sorted(json.loads(p.read_text())["node"] for p in cache.glob("entries/*/*.json"))


def test_a_node_declared_not_stored_is_computed_not_cached(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "plugin.py").write_text(PLUGIN)
    (tmp_path / "stored.yaml").write_text(RECIPE)
    cache = tmp_path / "cache"
    args = ["run", "stored.yaml", "--plugin", "plugin.py", "--cache-dir", str(cache), "--no-rrd"]
    assert main(args) == 0
    assert cached_nodes(cache) == ["total"]
    out = tmp_path / "outputs" / "stored"
    assert (out / "big.csv").read_text() == "x\n0.0\n1.0\n2.0\n3.0\n" and (
        out / "total.csv"
    ).read_text() == "sum\n6.0\n"
    capsys.readouterr()
    assert main(args) == 0  # current files: nothing computed, nothing written
    assert "up to date:" in capsys.readouterr().out
    (out / "big.csv").unlink()
    assert main([*args, "--output", "big"]) == 0  # computed again; total, not asked for, is not
    assert (out / "big.csv").read_text().startswith("x\n0.0") and cached_nodes(cache) == ["total"]
    assert main([*args, "--set", "big.n=2", "-q"]) == 0  # total runs and pulls big
    assert (out / "set_big.n=2" / "total.csv").read_text() == "sum\n1.0\n" and cached_nodes(cache) == ["total", "total"]
