"""The main job's simulation as bytes: sha256 (first 16 hex digits) of the rice_sim and egg_sim outputs of
graphs/ikura_don.yaml (positions, rotations, deformations, bends; particle positions, velocities, radii,
inverse masses, elements), run without the node cache. Equal digests before and after a solver change mean
the default solver is bit for bit the same (issue 45: 2026-12-06, every step of the solver rebuild).

    python benchmarks/xpbd_main_job_hash.py
"""

from __future__ import annotations

import hashlib
import time

import numpy as np

OUTPUTS = ("rice_sim.aggregate", "rice_sim.particles", "egg_sim.aggregate", "egg_sim.particles")


def digests(recipe_path: str = "graphs/ikura_don.yaml") -> dict[str, str]:
    from nodegraph.api import default_registry, load_recipe, run_recipe

    result = run_recipe(load_recipe(recipe_path, default_registry()), outputs=list(OUTPUTS), cache=None)
    out = {}
    for ref in OUTPUTS:
        value = result.output(ref)
        if ref.endswith("particles"):
            arrays = [value.positions, value.velocities, value.radii, value.inv_mass, value.element]
        else:
            arrays = [value.placement.positions, value.placement.rotations, value.deformations, value.bends]
        h = hashlib.sha256()
        for a in arrays:
            if a is not None:
                h.update(np.ascontiguousarray(a).tobytes())
        out[ref] = h.hexdigest()[:16]
    return out


def main() -> None:
    t = time.time()
    for ref, digest in digests().items():
        print(ref, digest)
    print(f"{time.time() - t:.0f} s")


if __name__ == "__main__":
    main()
