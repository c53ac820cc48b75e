"""Cluster layouts for a grain that gives way when squeezed (issue 46: cooked rice strains ≈ 25 % at 0.2 N and springs
back, Tomita via G, SPEC §3): for each candidate (particles per grain, layers through the thickness, stiffness,
iterations, substeps) the squeezed-grain set-up of ``validation.squeeze_xpbd`` at 0.05, 0.2 and 1 N, the grain's own
flattening and what is left of it 0.5 s after the plate is lifted, and the 300-grain stream heap of
``physics_at_defaults.heap_case`` (angle at 2.5 s and 7 s, solver seconds). One line per candidate into
benchmarks/measured/squeeze_candidates.jsonl, rendered in docs/validation.md by ``python tools/measured_tables.py``.

    python benchmarks/squeeze_candidates.py            # every candidate, with its heap (≈ 10 min on 2 cores)
    python benchmarks/squeeze_candidates.py --no-heap  # the squeeze only (≈ 2 min), prints, writes nothing
"""

import argparse
import json
import os
from datetime import UTC, datetime
from pathlib import Path

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

RECORD = Path(__file__).resolve().parent / "measured" / "squeeze_candidates.jsonl"
LOADS = (0.05, 0.2, 1.0)  # N per grain
# (name, particles per grain, layers, node parameters): today's default, the same count planar (cost), two layers at
# the defaults, at the stiffness δ = F/k asks for (100 N/m: 16 particles, 3.2·k·δ = 0.2 N at δ = 0.625 mm, 25 % of
# 2.5 mm), and that stiffness with the iterations or substeps a layered cluster needs to hold its shape
CANDIDATES = (
    ("today: one layer", 8, 1, {}),
    ("one layer, 16 particles", 16, 1, {}),
    ("two layers", 16, 2, {}),
    ("two layers, 100 N/m", 16, 2, {"stiffness": 100.0}),
    ("two layers, 100 N/m, 8 iterations", 16, 2, {"stiffness": 100.0, "iterations": 8}),
    ("two layers, 100 N/m, 32 iterations", 16, 2, {"stiffness": 100.0, "iterations": 32}),  # no heap: ≈ 8× the time
    ("two layers, 100 N/m, 40 substeps", 16, 2, {"stiffness": 100.0, "substeps": 40}),
)


def squeeze(particles: int, layers: int, params: dict) -> dict:
    """Plate strain (1 − plate height / its height at 1 mN) at each of ``LOADS``; at 0.2 N the grain's own
    flattening (1 − its thickness / the unloaded one) and what is left of it 0.5 s after the plate is lifted; the
    grains that left the plate."""
    from validation import squeeze_xpbd

    rest = squeeze_xpbd(0.001, particles, layers=layers, **params)
    runs = {f: squeeze_xpbd(f, particles, layers=layers, after=30 if f == 0.2 else 0, **params) for f in LOADS}
    mid = runs[0.2]
    return {
        "plate_strain": {str(f): round(1 - r["gap"] / rest["gap"], 3) for f, r in runs.items()},
        "flattening": round(1 - mid["loaded"] / mid["thickness"], 3),
        "left_after_lift": round(1 - mid["after"] / mid["thickness"], 3),
        "escaped": {str(f): r["escaped"] for f, r in runs.items()},
        "squeeze_seconds": round(sum(r["seconds"] for r in runs.values()), 1),
    }


def heap(particles: int, layers: int, params: dict) -> dict:
    """The 300-grain stream heap at 10 substeps (``validation.rice_heap``) with this candidate's clusters."""
    from validation import rice_heap

    params = {"particles_per_element": particles, "particle_layers": layers, **params}
    substeps = params.pop("substeps", 10)
    angles, seconds = rice_heap(300, True, frames=(150, 420), substeps=substeps, shape="stream", **params)
    (s25, hr25), (s7, hr7) = angles
    return {
        "hr_2_5": round(hr25, 1),
        "hr_7": round(hr7, 1),
        "surface_7": round(s7, 1),
        "heap_seconds": round(seconds, 1),
    }


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-heap", action="store_true", help="the squeeze only; print, write nothing")
    args = ap.parse_args(argv)
    lines = []
    for name, particles, layers, params in CANDIDATES:
        values = {"particles": particles, "layers": layers, **squeeze(particles, layers, params)}
        if not args.no_heap and params.get("iterations", 2) <= 8:
            values.update(heap(particles, layers, params))
        knobs = ", ".join(f"{k} {v:g}" for k, v in params.items()) or "xpbd defaults"
        print(f"{name}: {knobs} {values}", flush=True)
        lines.append(
            json.dumps(
                {
                    "what": name,
                    "knobs": knobs,
                    "values": values,
                    "unit": "strain (fraction), degrees, s",
                    "command": "python benchmarks/squeeze_candidates.py",
                    "load": f"{os.getloadavg()[0]:.1f}",
                    "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
                    "machine": f"{os.cpu_count()} cores",
                }
            )
        )
    if not args.no_heap:
        RECORD.write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
