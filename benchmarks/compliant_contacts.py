"""Compliant contacts (``squeeze_strain``, issue 46) measured: three library grains squeezed under a flat plate (and
the grid plate of the validation case) at 0.05 / 0.2 / 1 N, their springback once the plate is lifted, and a grain
dropped 10 mm onto another, at the xpbd node's defaults and at 4× its substeps, against rigid contacts. Writes
benchmarks/measured/compliant_contacts.jsonl (one line per row); ``python tools/measured_tables.py`` renders the
table in docs/validation.md.

    python benchmarks/compliant_contacts.py      # ≈ 2 min on 2 cores
    python benchmarks/compliant_contacts.py --heaps   # the 300-grain stream at 10 and 40 substeps, the 890-grain
                                                      # ball at 10 (physics_at_defaults.heap_case), ≈ 10 min;
                                                      # benchmarks/measured/compliant_heaps.jsonl
"""

import argparse
import json
import os
import time
from pathlib import Path

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from machine import stamp  # noqa: E402
from validation import drop_bounce, squeeze_xpbd  # noqa: E402

RECORD = Path(__file__).resolve().parent / "measured" / "compliant_contacts.jsonl"
HEAPS = RECORD.with_name("compliant_heaps.jsonl")
LOADS = (0.05, 0.2, 1.0)  # N per grain


def row(what: str, flat: bool, **params) -> dict:
    """One row: the plate's strain at each load against its height at 1 mN, the grains' top left pressed 0.5 s
    after the plate is lifted off 0.2 N (and how far they rose above it), and a 10 mm drop's rebound."""
    load0, start = os.getloadavg()[0], time.perf_counter()
    rest = squeeze_xpbd(0.001, flat=flat, **params)
    runs = {f: squeeze_xpbd(f, flat=flat, after=30 if f == 0.2 else 0, **params) for f in LOADS}
    lifted = runs[0.2]
    drop = drop_bounce(**params)
    given = ", ".join(f"{k} {v}" for k, v in params.items())
    return {
        "what": what,
        "knobs": given or "xpbd defaults",
        "values": {
            "strain": {str(f): round(1 - r["gap"] / rest["gap"], 3) for f, r in runs.items()},
            "escaped": sum(r["escaped"] for r in runs.values()),
            "passed": sum(r["above"] for r in runs.values()),
            "left_after_lift": round(1 - lifted["top_after"] / rest["top"], 4),
            "rise_after_lift": round(lifted["rise"], 3),
            "rebound": round(drop["rebound"], 3),
            "impact": round(drop["impact"], 1),
            "seconds": round(time.perf_counter() - start, 1),
        },
        "unit": "strain (fraction), mm, mm/s, s",
        "command": "python benchmarks/compliant_contacts.py",
        **stamp(load0),
    }


def heaps() -> list[dict]:
    """The heaps of physics_at_defaults at the node's defaults but compliant contacts: does a heap still rest?"""
    from physics_at_defaults import heap_case

    rows = []
    for shape, n, substeps in (("stream", 300, 10), ("stream", 300, 40), ("ball", 890, 10)):
        load0 = os.getloadavg()[0]
        case = heap_case(shape, n, substeps, squeeze_strain=25.0)
        rows.append({"what": case["case"], "substeps": substeps, **{k: case[k] for k in ("ours", "values")}})
        rows[-1].update(unit="degrees, s", command="python benchmarks/compliant_contacts.py --heaps", **stamp(load0))
        print(rows[-1]["what"], substeps, rows[-1]["ours"], flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--heaps", action="store_true", help="the heaps only (compliant_heaps.jsonl)")
    if parser.parse_args().heaps:
        HEAPS.write_text("".join(json.dumps(r, ensure_ascii=False) + "\n" for r in heaps()))
        return
    rows = [
        row("compliant, flat plate", True, squeeze_strain=25.0),
        row("compliant, flat plate, 4× substeps", True, squeeze_strain=25.0, substeps=40),
        row("compliant, flat plate, 8 iterations", True, squeeze_strain=25.0, iterations=8),
        row("compliant, grid plate (case (a) above)", False, squeeze_strain=25.0),
        row("rigid contacts, flat plate", True, squeeze_strain=0.0),
        row("rigid contacts, flat plate, 4× substeps", True, squeeze_strain=0.0, substeps=40),
    ]
    RECORD.write_text("".join(json.dumps(r, ensure_ascii=False) + "\n" for r in rows))
    for r in rows:
        print(r["what"], r["values"])


if __name__ == "__main__":
    main()
