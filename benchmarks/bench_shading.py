"""CDRF accuracy vs time — SPEC §4 eq. 7: the fitted approximation (θ×σ lookup table, what ``shade``
uses) and n-point quadrature of the convolution integral, against the exact closed form.

    python benchmarks/bench_shading.py [--quick]

Per method: max and RMS error over per-vertex (θ, σ) samples drawn like a rice scene's (σ = σ₀|κ|,
σ₀ at 15 % water, |κ| of grains ≈ 0–3 /mm), and the time to shade one frame of N vertices.
Writes benchmarks/results/bench_shading.{md,png}.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from nodes.shading.cdrf import CdrfTable, cdrf_exact, cdrf_quadrature, curvature_sigma, sigma0_from_water


def timed(fn, repeats):
    fn()
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="few vertices and methods (seconds)")
    args = parser.parse_args()
    n = 20_000 if args.quick else 300_000
    repeats = 1 if args.quick else 3
    rng = np.random.default_rng(0)
    theta = np.arccos(rng.uniform(-1, 1, n))
    sigma = curvature_sigma(rng.gamma(2.0, 0.6, n), sigma0_from_water(15.0, 0.15, 1.2))
    exact = cdrf_exact(theta, sigma)
    rows = [("exact (closed form, complex erf)", timed(lambda: cdrf_exact(theta, sigma), repeats), 0.0, 0.0)]
    lambert = np.maximum(np.cos(theta), 0)
    rows.append(
        (
            "Lambert (no CDRF)",
            timed(lambda: np.maximum(np.cos(theta), 0), repeats),
            np.abs(lambert - exact).max(),
            np.sqrt(np.mean((lambert - exact) ** 2)),
        )
    )
    for nodes in (4, 16) if args.quick else (4, 8, 16, 32, 64):
        chunk = slice(0, min(n, 100_000))
        t = (
            timed(lambda chunk=chunk, nodes=nodes: cdrf_quadrature(theta[chunk], sigma[chunk], nodes), repeats)
            * n
            / len(theta[chunk])
        )
        err = cdrf_quadrature(theta, sigma, nodes) - exact
        rows.append((f"quadrature n={nodes}", t, np.abs(err).max(), np.sqrt(np.mean(err**2))))
    for size in (16, 64, 128, 256) if args.quick else (8, 16, 32, 64, 128, 256):
        table = CdrfTable.build(size, max(2, size // 2))
        err = table(theta, sigma) - exact
        rows.append(
            (
                f"table {size}×{max(2, size // 2)}",
                timed(lambda table=table: table(theta, sigma), repeats),
                np.abs(err).max(),
                np.sqrt(np.mean(err**2)),
            )
        )

    lines = [
        f"CDRF eq. 7 per frame of {n:,} vertices (one light), best of {repeats}",
        "",
        "| method | time per frame (ms) | max error | RMS error |",
        "|---|---|---|---|",
    ]
    lines += [f"| {name} | {t * 1e3:.1f} | {emax:.2e} | {erms:.2e} |" for name, t, emax, erms in rows]
    text = "\n".join(lines)
    print(text)
    out = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or Path(__file__).parent / "results")
    out.mkdir(exist_ok=True)
    (out / "bench_shading.md").write_text(text + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for prefix, marker in (("quadrature", "o-"), ("table", "s-"), ("Lambert", "x")):
        pts = [(t * 1e3, erms) for name, t, _, erms in rows if name.startswith(prefix)]
        if pts:
            ax.loglog(*zip(*pts), marker, label=prefix)
    ax.axvline(rows[0][1] * 1e3, color="k", ls=":", label="exact closed form")
    ax.set_xlabel(f"time per frame of {n:,} vertices (ms)")
    ax.set_ylabel("RMS error vs exact")
    ax.legend()
    ax.set_title("CDRF (SPEC §4 eq. 7): accuracy vs time")
    fig.tight_layout()
    fig.savefig(out / "bench_shading.png", dpi=120)
    print(f"wrote {out / 'bench_shading.md'} and {out / 'bench_shading.png'}")


if __name__ == "__main__":
    main()
