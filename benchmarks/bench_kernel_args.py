"""Kernels with typed argument bundles against the same kernels with positional arrays (issue 23 part 3).

Lists every function in ``nodes/`` and ``nodegraph/`` with more than 12 parameters (node functions aside),
then times the refactored kernels of this tree and of a baseline commit side by side, in the same call:
compile time (first call in a fresh numba cache minus a warm call) and warm run time (median of
``--repeat`` calls), each case in its own process, the two trees taking turns. The output digests of
the two trees must match: the bundles change how arguments travel, not what is computed.

    python benchmarks/bench_kernel_args.py [--baseline REF] [--repeat 5] [--rounds 1] [--quick]

Cases (representative inputs, built with a fixed seed):
  refine    ``refine.refine_placement`` (2 passes) then ``refine.cull_placement``: the placement kernels
  flatten   ``contact_flattening.flatten`` on a block of overlapping grains
  shape     ``shape_matching.shape_match_project`` (linear and quadratic goals) and ``shape_match_goals``
  grid      ``spatial_hash.neighbour_lists`` (half and full rows)
"""

from __future__ import annotations

import argparse
import ast
import hashlib
import importlib
import inspect
import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

ROOT = Path(__file__).resolve().parent.parent
LIMIT = 12


def wide_functions(root: Path = ROOT, limit: int = LIMIT) -> list[tuple[str, str, int, int]]:
    """(file, function, line, parameters) of every function with more than ``limit`` parameters, node
    functions (decorated with ``@node(...)``: their parameters arrive as keywords) aside."""
    rows = []
    for package in ("nodes", "nodegraph"):
        for path in sorted((root / package).rglob("*.py")):
            for fn in ast.walk(ast.parse(path.read_text(), str(path))):
                if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                    continue
                if any(isinstance(d, ast.Call) and getattr(d.func, "id", None) == "node" for d in fn.decorator_list):
                    continue
                count = len(fn.args.posonlyargs) + len(fn.args.args) + len(fn.args.kwonlyargs)
                if count > limit:
                    rows.append((str(path.relative_to(root)), fn.name, fn.lineno, count))
    return rows


def digest(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:12]


# ---- cases: each returns a function that runs the kernels once and returns a digest of their outputs


def case_refine(quick: bool):
    import trimesh

    from nodegraph.values import Mesh
    from nodes.placement import mix_ratio, poisson_place, rotate
    from nodes.placement.element_templates import build_templates
    from nodes.placement.refine import RefineSettings, cull_placement, refine_placement
    from nodes.shapes import shape
    from nodes.values import ElementLibrary

    meshes = []
    for v in range(2):
        grain = trimesh.creation.icosphere(3)
        grain.apply_scale([1.1, 0.64 - 0.03 * v, 0.44 + 0.02 * v])
        meshes.append(Mesh.from_trimesh(grain, name=f"rice{v}"))
    library = ElementLibrary("rice", tuple(meshes))
    onigiri = shape.call(kind="onigiri", size=8.0 if quick else 16.0, resolution=4)["mesh"]
    placed = poisson_place.call(seed=1, shape=onigiri, r=0.35)["placement"]
    turned = rotate.call(seed=1, placement=placed)
    placement = mix_ratio.call(seed=1, placement=turned, libraries=[library])["placement"]
    templates = build_templates((library,), 0.02, 64, 64)
    rng = np.random.default_rng(1)
    orders = [rng.permutation(len(placement)) for _ in range(2)]
    ranges = np.array([library.refine_range])

    def run():
        refined = refine_placement(placement, templates, ranges, RefineSettings(), orders)
        gan = refine_placement(placement, templates, ranges, RefineSettings(cost="gan", spacing=0.35), orders[:1])
        keep, depth = cull_placement(refined, templates, 0.05, 0.0)
        return digest(refined.positions, refined.overlap, gan.positions, keep, depth)

    return run, f"{len(placement)} elements"


def case_flatten(quick: bool):
    import dataclasses

    import trimesh

    import nodes
    from nodegraph.values import Mesh
    from nodes.values import Aggregate, ElementLibrary, Placement

    # the module's home in the tree being timed: a baseline from before nodes/contact_shaping has it in simulation
    home = "contact_shaping" if (Path(nodes.__file__).parent / "contact_shaping").is_dir() else "simulation"
    flatten = importlib.import_module(f"nodes.{home}.contact_flattening").flatten

    side = 4 if quick else 7
    rng = np.random.default_rng(3)
    grid = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3).astype(float)
    positions = grid * np.array([5.2, 2.6, 1.8]) + rng.normal(0.0, 0.15, grid.shape)  # grains 6 × 3 × 2 mm
    n = len(positions)
    angles = rng.uniform(-0.3, 0.3, n)
    rotations = np.zeros((n, 3, 3))
    rotations[:, 0, 0], rotations[:, 0, 1] = np.cos(angles), -np.sin(angles)
    rotations[:, 1, 0], rotations[:, 1, 1] = np.sin(angles), np.cos(angles)
    rotations[:, 2, 2] = 1.0
    mesh = trimesh.creation.icosphere(4)
    mesh.apply_scale([3.0, 1.5, 1.0])
    library = ElementLibrary("rice", (Mesh.from_trimesh(mesh, name="grain"),))
    placement = Placement(positions, np.tile([0.0, 0.0, 1.0], (n, 1)), kind_names=("rice",))
    aggregate = Aggregate(dataclasses.replace(placement, rotations=rotations), (library,))

    def run():
        dents, figures = flatten(aggregate)
        return digest(dents.element, dents.vertex, dents.offset)

    return run, f"{n} grains"


def _clusters(count: int, size: int, seed: int):
    rng = np.random.default_rng(seed)
    start = np.arange(count + 1, dtype=np.int64) * size
    local = rng.normal(0.0, 1.0, (count * size, 3)) * np.array([1.5, 0.8, 0.5])
    centres = np.repeat(rng.uniform(0.0, 50.0, (count, 3)), size, axis=0)
    w = np.full(count * size, 1.0)
    q_rest = local.copy()
    for c in range(count):
        q_rest[start[c] : start[c + 1]] -= q_rest[start[c] : start[c + 1]].mean(axis=0)
    x = centres + q_rest + rng.normal(0.0, 0.05, q_rest.shape)
    return x, w, q_rest, start


def case_shape(quick: bool):
    from nodes.simulation import model, shape_matching

    try:
        from nodes.simulation.state import StateArrays
    except ImportError:  # before issue 45
        StateArrays = None

    count, size = (500, 24) if quick else (4000, 24)
    x0, w, q_rest, start = _clusters(count, size, 5)
    moments = model.RestMoments(*shape_matching.rest_moments(q_rest, w, start))
    fit = model.QuadraticFit(*shape_matching.quadratic_moments(q_rest, w, start))
    awake = np.ones(len(w), np.bool_)
    goals_params = inspect.signature(shape_matching.shape_match_goals.py_func).parameters
    project_params = inspect.signature(shape_matching.shape_match_project.py_func).parameters

    def goals(x, quats, out):
        if "aqq_pinv" in goals_params:  # positional arrays (before issue 23)
            shape_matching.shape_match_goals(
                x, w, q_rest, start, quats, moments.aqq_pinv, moments.null_proj, 0.3, 8, fit.qt, fit.qpinv,
                fit.flags, out,
            )  # fmt: skip
        else:
            shape_matching.shape_match_goals(x, w, q_rest, start, quats, *moments.args(), 0.3, 8, *fit.args(), out)

    def run():
        results = []
        for quadratic in ((), fit.args()):
            x = x0.copy()
            quats = np.tile([1.0, 0.0, 0.0, 0.0], (count, 1))
            lam = np.zeros_like(x)
            worst = 0.0
            for _ in range(4):  # as the solver: the same call as solver.py writes it
                if "state" in project_params:  # named bundles (issue 45)
                    state = StateArrays(x, x, x, x, quats, np.zeros(count, np.bool_), awake, awake, x)
                    arrays = model.ModelArrays(w, w, np.zeros(len(w), np.int64), start, q_rest)
                    rule = shape_matching.MatchRule(1e-6, 0.3, 8)
                    worst = shape_matching.shape_match_project(state, arrays, *moments.args(), lam, rule, *quadratic)
                else:
                    worst = shape_matching.shape_match_project(
                        x, quats, awake, w, q_rest, start, *moments.args(), lam, 1e-6, 0.3, 8, *quadratic
                    )
            results += [x, quats, lam, np.array([worst])]
        out = np.empty_like(x0)
        goals(x0, np.tile([1.0, 0.0, 0.0, 0.0], (count, 1)), out)
        return digest(*results, out)

    return run, f"{count} clusters × {size}"


def case_grid(quick: bool):
    from nodes.simulation.spatial_hash import neighbour_lists

    n = 20_000 if quick else 200_000
    rng = np.random.default_rng(7)
    x = rng.uniform(0.0, (n / 0.5) ** (1 / 3) * 0.5, (n, 3))
    r = np.full(n, 0.25)
    elem = np.arange(n, dtype=np.int64) // 8
    n_active = n - n // 20

    def pairs(lists):
        """The listed (particle, partner) pairs in row order, whichever way the rows are stored: by particle id
        (before 2026-11-26: start, nbr, cell_start, order, dims) or by sorted position (start, nbr, at, ...)."""
        start, nbr, *rest = lists
        order = rest[-2]
        owner = order if len(rest) == 4 else np.arange(len(order))
        return np.repeat(owner, np.diff(start)), nbr

    def run():
        half = neighbour_lists(x, r, elem, 0.01, 0.51, n_active, True)
        full = neighbour_lists(x, r, elem, 0.01, 0.51, n_active, False)
        (hi, hj), (fi, fj) = pairs(half), pairs(full)
        key_h, key_f = np.lexsort((hj, hi)), np.lexsort((fj, fi))
        return digest(hi[key_h], hj[key_h], fi[key_f], fj[key_f])

    return run, f"{n} particles"


CASES = {"refine": case_refine, "flatten": case_flatten, "shape": case_shape, "grid": case_grid}


def measure(case: str, repeat: int, quick: bool) -> dict:
    """In this process (fresh numba cache): build the inputs, time the first call and ``repeat`` warm ones."""
    run, size = CASES[case](quick)
    start = time.perf_counter()
    first = run()
    first_s = time.perf_counter() - start
    warm = []
    for _ in range(repeat):
        start = time.perf_counter()
        again = run()
        warm.append(time.perf_counter() - start)
        if again != first:
            raise AssertionError(f"{case}: a warm call gave {again}, the first {first}")
    run_s = statistics.median(warm)
    return {"size": size, "compile_s": first_s - run_s, "run_s": run_s, "digest": first}


def in_child(tree: Path, case: str, repeat: int, quick: bool) -> dict:
    """``measure`` in a fresh process that imports the packages of ``tree`` with an empty numba cache."""
    with tempfile.TemporaryDirectory(prefix="numba-bench-") as cache:
        env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_CACHE_DIR=cache)
        args = [sys.executable, __file__, "--child", case, "--repeat", str(repeat)] + (["--quick"] if quick else [])
        out = subprocess.run(args, env=env, cwd=tree, capture_output=True, text=True)
        if out.returncode:
            raise RuntimeError(f"{case} in {tree} failed:\n{out.stderr[-3000:]}")
        return json.loads(out.stdout.strip().splitlines()[-1])


def checkout(ref: str, into: Path) -> Path:
    """The packages of commit ``ref`` unpacked into ``into`` (git archive: no work tree needed)."""
    archive = into / "tree.tar"
    with archive.open("wb") as f:
        subprocess.run(["git", "archive", ref, "nodes", "nodegraph"], cwd=ROOT, stdout=f, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(into, filter="data")
    return into


BEFORE_BUNDLES = "b3bf1f5"  # the last commit whose kernels took their arrays one by one (issue 23)
QUICK_CASES = "flatten,grid"  # compiling every case in both trees is ≈ 190 CPU s, over the quick-mode budget


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default=BEFORE_BUNDLES, help=f"commit to compare with (default {BEFORE_BUNDLES})")
    parser.add_argument("--repeat", type=int, default=5, help="warm calls per case (median)")
    parser.add_argument("--rounds", type=int, default=1, help="processes per case and tree (taking turns)")
    parser.add_argument("--cases", help=f"comma-separated, of {', '.join(CASES)} (default all; --quick: {QUICK_CASES})")
    parser.add_argument("--quick", action="store_true", help="smaller inputs, the two cheapest cases to compile")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(measure(args.child, args.repeat, args.quick)))
        return

    wide = wide_functions()
    print(f"functions with more than {LIMIT} parameters in nodes/ and nodegraph/ (node functions aside): {len(wide)}")
    for path, name, line, count in wide:
        print(f"  {count:3d}  {path}:{line}  {name}")
    with tempfile.TemporaryDirectory(prefix="bench-baseline-") as tmp:
        trees = {"before": checkout(args.baseline, Path(tmp)), "after": ROOT}
        threads = os.environ.get("NUMBA_NUM_THREADS") or os.cpu_count()
        print(f"\nbefore = {args.baseline}, after = this tree; numba threads {threads}")
        header = f"{'case':8} {'input':22} {'compile before':>15} {'after':>8} {'run before':>11} {'after':>8}  outputs"
        print(header)
        print("-" * len(header))
        for case in (args.cases or (QUICK_CASES if args.quick else ",".join(CASES))).split(","):
            results = {"before": [], "after": []}
            for _ in range(args.rounds):
                for name, tree in trees.items():
                    results[name].append(in_child(tree, case, args.repeat, args.quick))
            b, a = results["before"], results["after"]

            def med(rows, key):
                return statistics.median(r[key] for r in rows)

            same = {r["digest"] for r in b} == {r["digest"] for r in a} and len({r["digest"] for r in b}) == 1
            print(
                f"{case:8} {a[0]['size']:22} {med(b, 'compile_s'):14.2f}s {med(a, 'compile_s'):7.2f}s "
                f"{med(b, 'run_s'):10.3f}s {med(a, 'run_s'):7.3f}s  {'identical' if same else 'DIFFER'} "
                f"({a[0]['digest']})"
            )


if __name__ == "__main__":
    main()
