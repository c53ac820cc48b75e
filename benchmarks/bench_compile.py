"""Seconds numba spends compiling each kernel on a first run (empty numba cache), from numba's own
``numba:compile`` events, so the kernels worth compiling less are named (issue 27: first run ≤ 90 s).

The recipe runs in a fresh process with an empty NUMBA_CACHE_DIR and an empty node cache; each kernel's
row is its outermost compilation (helpers it inlines or calls are compiled inside it and counted there).
The CPU column (the compiling thread's own CPU time) moves less with the load of a shared machine than the
wall seconds. Run: python benchmarks/bench_compile.py [--quick] [--full] [--record] [--recipe graphs/ikura_don.yaml]
(--quick: one tiny kernel in a throw-away plug-in, a smoke run of the machinery; --full: the recipe at full size,
not --draft; --record: also write what each node type compiled into the node package's kernel_signatures.json,
the list the first run's compile-ahead worker reads, nodegraph/compile_ahead.py.)
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RECORD = "kernel_signatures.json"
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")

# Runs inside the fresh process: records every outermost compilation, then runs the CLI.
PROBE = """
import json, sys, time
from numba.core import event
from nodegraph import compile_progress
from nodegraph.compile_ahead import encode_types

rows, depth, start, node = [], [0], [0.0, 0.0], [""]
watch_init = compile_progress.CompileWatch.__init__


def watching(self, reporter, label):
    node[0] = label  # the node instance whose kernels compile now
    watch_init(self, reporter, label)


compile_progress.CompileWatch.__init__ = watching

class Timer(event.Listener):
    def on_start(self, ev):
        if depth[0] == 0:
            start[:] = time.perf_counter(), time.thread_time()
        depth[0] += 1

    def on_end(self, ev):
        depth[0] -= 1
        if depth[0] == 0:
            func = ev.data["dispatcher"].py_func
            name = f"{func.__module__}.{func.__qualname__}"
            seconds = time.perf_counter() - start[0], time.thread_time() - start[1]
            rows.append((name, str(ev.data["args"]), *seconds, node[0], func.__module__, func.__qualname__,
                         encode_types(ev.data["args"])))

event.register("numba:compile", Timer())
from nodegraph.cli import main
wall = time.perf_counter()
code = main(json.loads(sys.argv[1]))
json.dump({"code": code, "wall": time.perf_counter() - wall, "rows": rows}, open(sys.argv[2], "w"))
"""

QUICK_PLUGIN = '''
import numpy as np
from numba import njit
from nodegraph import Out, node
from nodegraph.values import Table

@njit(cache=True)
def double(values):
    return 2.0 * values

@node("compile_probe", outputs={"table": Out(Table, "doubled")})
def compile_probe(ctx):
    """One numba kernel."""
    return Table({"x": double(np.arange(4.0))})
'''
QUICK_RECIPE = "name: compile_probe\nseed: 1\noutputs: [probe.table]\nnodes:\n  probe:\n    type: compile_probe\n"


ARRAY = re.compile(r"Array\((\w+), (\d+), '(\w)', (True|False), aligned=True\)")
FIELD = re.compile(r"(readonly )?array\((\w+), (\d+)d, (\w)\)")  # an array inside a typed bundle (NamedTuple)
SHORT = {"float64": "f64", "int64": "i64", "bool": "bool"}


def compact(types: str) -> str:
    """numba's argument types, short: ``f64[2d]``; ``ro`` marks a read-only array (a specialisation of its own)."""

    def one(match) -> str:
        kind, ndim, layout, readonly = match.groups()
        return f"{'ro ' if readonly == 'True' else ''}{SHORT.get(kind, kind)}[{ndim}d{'' if layout == 'C' else layout}]"

    def field(match) -> str:
        readonly, kind, ndim, layout = match.groups()
        return f"{'ro ' if readonly else ''}{SHORT.get(kind, kind)}[{ndim}d{'' if layout == 'C' else layout}]"

    text = FIELD.sub(field, ARRAY.sub(one, types)).replace("omitted(default=None)", "-")
    return (text[1:-1] if text.startswith("(") and text.endswith(")") else text).rstrip(",")


def first_run(cli_args: list[str], work: Path) -> dict:
    """The CLI run in a fresh process with empty numba and node caches: its compilations and wall time."""
    # every kernel compiles in this process, where it is timed: no compiling ahead in a second one
    env = dict(os.environ, NUMBA_CACHE_DIR=str(work / "numba"), NODEGRAPH_COMPILE_AHEAD="off")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    out = work / "compiles.json"
    subprocess.run([sys.executable, "-c", PROBE, json.dumps(cli_args), str(out)], env=env, cwd=ROOT, check=True)
    return json.loads(out.read_text())


def record(recipe_path: str, rows: list) -> None:
    """The kernels each node type compiled, with the effects it received, into the node package's record
    (``nodegraph.compile_ahead``): entries of other node types or other effects are kept."""
    from nodegraph.compile_ahead import record_path
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    recipe = load_recipe(recipe_path, default_registry())
    found: dict[tuple[str, tuple[str, ...]], list] = {}
    paths = {}
    for *_, label, module, qualname, args in rows:
        spec = recipe.nodes[label.split("[")[0]].spec
        key = spec.type_name, tuple(sorted(spec.effects & recipe.effects))
        paths[key] = record_path(spec)
        kernels = found.setdefault(key, [])
        if [module, qualname, args] not in kernels:
            kernels.append([module, qualname, args])
    for path in set(paths.values()):
        kept = json.loads(path.read_text()) if path.exists() else {}
        for (type_name, effects), kernels in found.items():
            if paths[type_name, effects] != path:
                continue
            entries = [e for e in kept.get(type_name, []) if e["effects"] != list(effects)]
            kept[type_name] = [*entries, {"effects": list(effects), "kernels": kernels}]
        path.write_text(json.dumps(dict(sorted(kept.items())), indent=1) + "\n")
        print(f"recorded {sum(len(k) for k in found.values())} kernels of {len(found)} node types in {path}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--recipe", default="graphs/ikura_don.yaml")
    ap.add_argument("--full", action="store_true", help="the recipe at full size (default: --draft)")
    ap.add_argument("--record", action="store_true", help=f"write the kernels into {RECORD} (implies --full)")
    args = ap.parse_args()
    args.full = args.full or args.record
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if args.quick:
            (work / "probe.py").write_text(QUICK_PLUGIN)
            (work / "probe.yaml").write_text(QUICK_RECIPE)
            recipe, extra = str(work / "probe.yaml"), ["--plugin", str(work / "probe.py")]
        else:
            recipe, extra = args.recipe, [] if args.full else ["--draft"]
        cli = ["run", recipe, *extra, "--cache-dir", str(work / "cache"), "--no-rrd", "--quiet"]
        cli += ["--out-dir", str(work / "out")]
        started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
        load = os.getloadavg()[0]
        result = first_run(cli, work)
    assert result["code"] == 0, f"the run failed (exit {result['code']})"
    if args.record:
        record(recipe, result["rows"])
    rows = sorted(result["rows"], key=lambda row: -row[2])
    total = sum(row[2] for row in rows)
    cpu = sum(row[3] for row in rows)
    what = "a one-kernel plug-in" if args.quick else f"nodegraph run {recipe}{'' if args.full else ' --draft'}"
    lines = [
        f"first run of `{what}` with an empty numba cache: "
        f"{result['wall']:.1f} s wall, {total:.1f} s compiling {len(rows)} kernel specialisations "
        f"({cpu:.1f} s of the compiling thread's CPU time)",
        "",
        "| kernel | argument types | compile s | CPU s | share |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| `{name}` | {compact(types)} | {seconds:.2f} | {thread:.2f} | {seconds / total:.0%} |"
        for name, types, seconds, thread, *_ in rows
    ]
    lines += [
        "",
        f"started {started}, load average {load:.2f} at the start and {os.getloadavg()[0]:.2f} at the end "
        f"(1 min) on {os.cpu_count()} cores",
    ]
    table = "\n".join(lines)
    print(table)
    RESULTS.mkdir(parents=True, exist_ok=True)
    suffix = "_quick" if args.quick else "_full" if args.full else ""
    (RESULTS / f"bench_compile{suffix}.md").write_text(table + "\n")


if __name__ == "__main__":
    main()
