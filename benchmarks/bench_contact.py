"""Contact deformation against the flattening it replaces — issue 25: per food recipe, the exported .glb judged by
the independent checkers (overlap depth by the winding-number and the pseudonormal inside tests, folded face pairs,
watertight share), each element's volume against its volume before the contact step, and the contact steps' time.

    python benchmarks/bench_contact.py CHECKERS_DIR                      # every food recipe, reduced sizes
    python benchmarks/bench_contact.py CHECKERS_DIR ikura_don --full     # the main job at full size
    python benchmarks/bench_contact.py --quick                           # the reduced rice bowl (CI smoke run)
    python benchmarks/bench_contact.py ../shared/tools ikura_don --full --time 2 --work DIR  # CPU s of each step

CHECKERS_DIR holds ``overlap_check.py`` and ``mesh_quality.py`` (they need trimesh, scipy and libigl): the argument,
else ``$NODEGRAPH_CHECKERS``, else the project's ``../shared/tools`` beside the checkout where it holds them. Without
them ``--quick`` runs the recipe and measures the volumes, and says the checkers' columns were skipped (a clean
clone has no ``../shared/tools``); the other modes stop and say where to point. "before" runs
the recipe with its contact steps as ``flatten_contacts``, "after" as ``deform_contacts`` (the recipes' own; both
take the settings the recipes give); both share one node cache, so the simulation runs once. One JSON line per run.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

REPO = Path(__file__).resolve().parents[1]
CHECKERS_ENV_VAR = "NODEGRAPH_CHECKERS"


def _load_bench_scenes():
    """``benchmarks/bench_scenes.py`` (the reduced sizes), loaded from its file: sys.path is left as it is."""
    spec = importlib.util.spec_from_file_location("bench_scenes", Path(__file__).with_name("bench_scenes.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


bench_scenes = _load_bench_scenes()
# --quick runs the reduced rice bowl (the cheapest food recipe; the reduced main job is tests/scenes' work) with its own
# contact step and the checkers: the main job took up to 226 CPU s where the numba cache is cold (compiling is ≈ 164
# CPU s of the whole pipeline, docs/performance.md)
QUICK_CPU_S = 360
RECIPES = ("ikura_don", "rice_bowl", "onigiri", "onigiri_cylinder", "sushi", "kakigori", "rice_bunny", "rice_chestnut")


EXPORT = ["export.formats=[glb]"]


def overrides(name: str, full: bool) -> list[str]:
    """The reduced sizes of ``benchmarks/bench_scenes.py`` (the bunny: its draft block, a small cut preview)."""
    small = ["cut_preview.width=64", "cut_preview.height=48", "cut_preview.samples=1"] if name == "rice_bunny" else []
    if full:  # the element counts in full; the pictures tiny (the checkers read the .glb)
        return bench_scenes.PREVIEW + small + EXPORT
    if name == "rice_bunny":
        keep = [o for o in bench_scenes.draft_overrides(name) if ".wall_cells" not in o and "preview" not in o]
        return keep + bench_scenes.PREVIEW[:3] + small + EXPORT
    return [o for o in bench_scenes._quick(name) if not o.startswith("measure.")] + EXPORT


def recipe_file(name: str, variant: str) -> Path:
    """A copy of the recipe beside it (its assets are relative) with its contact steps of one type: "before"
    ``flatten_contacts``, "after" ``deform_contacts``."""
    path = REPO / "graphs" / f"{name}.yaml"
    types = ("deform_contacts", "flatten_contacts") if variant == "before" else ("flatten_contacts", "deform_contacts")
    text = path.read_text().replace(f"type: {types[0]}", f"type: {types[1]}")
    copy = path.with_name(f".{variant}_{name}.yaml")
    copy.write_text(text)
    return copy


def volume(mesh) -> float:
    import trimesh

    faces = mesh.faces if mesh.parts is None else mesh.faces[mesh.parts == 0]
    return trimesh.Trimesh(mesh.vertices, faces, process=False).volume


def measure(name: str, variant: str, full: bool, checkers: Path | None, work: Path) -> dict:
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    path = recipe_file(name, variant)
    try:
        recipe = load_recipe(path, default_registry(), overrides(name, full))
    finally:
        path.unlink()
    steps = [n for n, e in recipe.nodes.items() if e.spec.type_name in ("flatten_contacts", "deform_contacts")]
    inputs = {s: str(recipe.nodes[s].inputs["aggregate"][0]) for s in steps}
    # a cull_crossing after a step removes the elements still crossing: the volume is judged on those it keeps
    culls = {
        str(e.inputs["aggregate"][0]).split(".")[0]: n
        for n, e in recipe.nodes.items()
        if e.spec.type_name == "cull_crossing"
    }
    wanted = [str(w) for w in recipe.outputs] + [f"{s}.aggregate" for s in steps] + list(inputs.values())
    wanted += [f"{c}.aggregate" for c in culls.values()]
    out = work / f"{name}_{variant}"
    start = time.perf_counter()
    result = run_recipe(recipe, outputs=wanted, cache=Cache(work / f"cache_{name}"), out_dir=out)
    total = time.perf_counter() - start
    errors = []
    removed = 0
    for s in steps:
        after, before = result.output(f"{s}.aggregate"), result.output(inputs[s])
        rows = range(len(after.placement))
        if s in culls:
            kept = {p.tobytes() for p in result.output(f"{culls[s]}.aggregate").placement.positions}
            rows = [i for i in rows if after.placement.positions[i].tobytes() in kept]
            removed += len(after.placement) - len(rows)
        errors += [volume(after.element_mesh(i)) / volume(before.element_mesh(i)) - 1.0 for i in rows]
    errors = np.abs(np.array(errors))
    glb = out / f"{recipe.nodes['export'].params['basename']}.glb"
    row = {
        "recipe": name,
        "variant": variant,
        "contact_s": round(sum(r.seconds for r in result.records if r.node in steps), 2),
        "contact_cpu_s": round(sum(r.cpu_seconds or 0.0 for r in result.records if r.node in steps), 2),
        "total_s": round(total, 1),
        "vol_err_p95": round(float(np.percentile(errors, 95)), 4),
        "vol_err_max": round(float(errors.max()), 4),
        "over_2pct": int((errors > 0.02).sum()),
        "elements": len(errors),
        "removed_crossing": removed,
    }
    if checkers is None:
        row["checkers"] = "skipped"
        return row
    for sign in ("winding", "pseudonormal"):
        run = [sys.executable, str(checkers / "overlap_check.py"), str(glb), "--sign", sign]
        line = subprocess.run(run, capture_output=True, text=True).stdout.strip().splitlines()[-1]
        row[sign] = line.split("overlap depth / length: ")[-1]
    run = [sys.executable, str(checkers / "mesh_quality.py"), str(glb)]
    row["quality"] = subprocess.run(run, capture_output=True, text=True).stdout.strip().split(": ", 1)[-1]
    return row


def time_steps(name: str, full: bool, work: Path, repeat: int) -> list[dict]:
    """Each contact step of the recipe run as ``flatten_contacts`` and as ``deform_contacts`` on its cached input,
    in turn, ``repeat`` times in one process (the simulation runs once, or not at all with a warm ``--work``)."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
    from nodes.contact_shaping.deform_contacts import deform_contacts
    from nodes.contact_shaping.flatten_contacts import flatten_contacts

    path = recipe_file(name, "after")
    try:
        recipe = load_recipe(path, default_registry(), overrides(name, full))
    finally:
        path.unlink()
    steps = [n for n, e in recipe.nodes.items() if e.spec.type_name == "deform_contacts"]
    effects = tuple(e for e in recipe.effects if e in ("contact", "collider"))
    rows = []
    for step in steps:
        wires = {k: [str(w) for w in v] for k, v in recipe.nodes[step].inputs.items()}
        result = run_recipe(recipe, outputs=[w for v in wires.values() for w in v], cache=Cache(work / f"cache_{name}"))
        given = {
            k: result.output(v[0]) if k == "aggregate" else [result.output(w) for w in v] for k, v in wires.items()
        }
        params = recipe.nodes[step].params
        for _ in range(repeat):
            for spec in (flatten_contacts, deform_contacts):
                start = time.process_time()
                spec.call(effects=effects, **given, **{k: v for k, v in params.items() if k in spec.params})
                rows.append(
                    {"recipe": name, "step": step, "node": spec.type_name, "cpu_s": time.process_time() - start}
                )
    return rows


def find_checkers(given: Path | None) -> Path | None:
    """The folder of ``overlap_check.py`` and ``mesh_quality.py``: ``given``, else ``$NODEGRAPH_CHECKERS``, else
    ``../shared/tools`` beside the checkout; None where that folder does not hold them."""
    folder = given or (Path(os.environ[CHECKERS_ENV_VAR]) if os.environ.get(CHECKERS_ENV_VAR) else None)
    folder = folder or REPO.parent / "shared" / "tools"
    return folder if (folder / "overlap_check.py").is_file() and (folder / "mesh_quality.py").is_file() else None


def main(argv: list[str] | None = None) -> int:
    import tempfile

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "checkers",
        type=Path,
        nargs="?",
        help=f"folder of overlap_check.py and mesh_quality.py (default: ${CHECKERS_ENV_VAR}, else ../shared/tools "
        "beside the checkout)",
    )
    parser.add_argument("recipes", nargs="*", default=list(RECIPES))
    parser.add_argument("--full", action="store_true", help="full sizes (minutes per recipe on 2 cores)")
    parser.add_argument("--quick", action="store_true", help="the reduced rice bowl only (a smoke run)")
    parser.add_argument("--variants", help="before,after (default; --quick: after, the recipes' own contact step)")
    parser.add_argument("--time", type=int, metavar="N", help="time each contact step as both nodes, N times in turn")
    parser.add_argument("--work", type=Path, help="keep the node caches and scenes here (re-runs reuse the simulation)")
    args = parser.parse_args(argv)
    if args.quick:
        args.recipes = ["rice_bowl"]
    variants = args.variants or ("after" if args.quick else "before,after")
    checkers = find_checkers(args.checkers)
    if checkers is None:
        where = args.checkers or os.environ.get(CHECKERS_ENV_VAR) or REPO.parent / "shared" / "tools"
        missing = (
            f"no overlap_check.py and mesh_quality.py in {where}: give their folder as CHECKERS_DIR or "
            f"${CHECKERS_ENV_VAR}"
        )
        if not (args.quick or args.time):  # timing the steps needs no checker
            parser.error(missing)
        if not args.time:
            print(f"checkers skipped ({missing}): the volumes only", file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory(prefix="bench-contact-") as tmp:
        work = args.work or Path(tmp)
        if args.time:
            for name in args.recipes:
                for row in time_steps(name, args.full, work, args.time):
                    print(json.dumps(row | {"cpu_s": round(row["cpu_s"], 2)}), flush=True)
            return 0
        for name in args.recipes:
            for variant in variants.split(","):
                print(json.dumps(measure(name, variant, args.full, checkers, work)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
