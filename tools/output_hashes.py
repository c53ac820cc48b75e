"""Hash every output of every shipped recipe at its reduced test size: a before/after table for refactors.

    python tools/output_hashes.py [--json FILE] [--compare BEFORE.json]

Each node instance's outputs are hashed by content: arrays (dtype, shape, bytes), plain fields, and
the value type's *class name* (not its module, so a type moved between packages hashes the same).
Files the recipe writes (.glb, .usdc, .png, ...) are hashed by their bytes.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]

# The reduced sizes the tests run the recipes at (tests/*/test_recipe*.py), plus rice_bowl and onigiri.
SMALL = {
    "rice_grains": [
        "japonica_spheres.variants=3",
        "japonica_volume.resolution=24",
        "japonica_grain.target_faces=400",
        "indica_spheres.variants=2",
        "aromatic_spheres.variants=2",
        "indica_volume.resolution=24",
        "aromatic_volume.resolution=24",
    ],
    "ikura_don": [
        "rice_place.r=3.0",
        "rice_sim.frames=2",
        "egg_sim.frames=2",
        "egg_place.r=4.0",
        "grain_mesh.target_faces=200",
        "preview.width=64",
        "preview.height=48",
        "preview.samples=1",
    ],
    "rice_bowl": [
        "rice_place.r=3.0",
        "rice_sim.frames=2",
        "grain_mesh.target_faces=200",
        "preview.width=64",
        "preview.height=48",
        "preview.samples=1",
    ],
    "onigiri": [
        "onigiri.size=10.0",
        "press.frames=2",
        "grain_spheres.variants=2",
        "preview.width=64",
        "preview.height=48",
        "preview.samples=1",
    ],
    "pile_onigiri": ["grain_spheres.variants=2", "grain_volume.resolution=24", "onigiri.size=6.0"],
    "rice_bunny": [
        "bunny.size=20.0",
        "grain_spheres.variants=2",
        "grain_volume.resolution=24",
        "press.frames=3",
        "preview.width=48",
        "preview.height=36",
        "preview.samples=1",
    ],
    "water_series": [
        "mound.size=4.0",
        "grain_spheres.variants=2",
        "grain_volume.resolution=24",
        "press.frames=2",
        "preview_00.width=48",
        "preview_00.height=48",
        "preview_00.samples=1",
        "preview_08.width=48",
        "preview_08.height=48",
        "preview_08.samples=1",
        "preview_16.width=48",
        "preview_16.height=48",
        "preview_16.samples=1",
        "preview_24.width=48",
        "preview_24.height=48",
        "preview_24.samples=1",
    ],
}


def _feed(h, obj) -> None:
    if isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        h.update(f"A{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(f"V{type(obj).__qualname__}".encode())
        for f in dataclasses.fields(obj):
            h.update(f.name.encode())
            _feed(h, getattr(obj, f.name))
    elif isinstance(obj, (list, tuple)):
        h.update(f"L{len(obj)}".encode())
        for v in obj:
            _feed(h, v)
    elif isinstance(obj, dict):
        h.update(f"D{len(obj)}".encode())
        for k in sorted(obj):
            h.update(str(k).encode())
            _feed(h, obj[k])
    elif isinstance(obj, float):
        h.update(f"F{obj.hex()}".encode())
    else:
        h.update(f"S{obj!r}".encode())


def value_hash(value) -> str:
    h = hashlib.sha256()
    _feed(h, value)
    return h.hexdigest()[:16]


def recipe_hashes(name: str, overrides: list[str]) -> dict[str, str]:
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    recipe = load_recipe(REPO / "graphs" / f"{name}.yaml", default_registry(), overrides=overrides)
    with tempfile.TemporaryDirectory() as tmp:
        result = run_recipe(recipe, cache=Cache(Path(tmp) / "cache"), out_dir=Path(tmp) / "out")
        out = {}
        for inst in sorted(result.values):
            for port, value in result.values[inst].items():
                out[f"{inst.label}.{port}"] = value_hash(value)
        for path in sorted(result.files):
            if path.suffix == ".npz":  # the codec's field tree names the value's module: hashed above by content
                continue
            out[f"file:{path.name}"] = hashlib.sha256(path.read_bytes()).hexdigest()[:16]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, help="write the hashes here")
    ap.add_argument("--compare", type=Path, help="a previous --json file: print the before/after table")
    ap.add_argument("--only", nargs="*", help="recipes to run (default: all)")
    args = ap.parse_args(argv)
    hashes = {
        name: recipe_hashes(name, overrides) for name, overrides in SMALL.items() if not args.only or name in args.only
    }
    if args.json:
        args.json.write_text(json.dumps(hashes, indent=1, sort_keys=True))
    before = json.loads(args.compare.read_text()) if args.compare else None
    print("| recipe | outputs hashed | identical | differ |")
    print("|---|---|---|---|")
    for name, now in hashes.items():
        if before is None:
            print(f"| {name} | {len(now)} | — | — |")
            continue
        old = before.get(name, {})
        same = [k for k in now if old.get(k) == now[k]]
        differ = [k for k in now if k in old and old[k] != now[k]]
        print(f"| {name} | {len(now)} | {len(same)} | {', '.join(differ) or '—'} |")
        missing = sorted(set(old) ^ set(now))
        if missing:
            print(f"|   ↳ only on one side | {', '.join(missing)} | | |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
