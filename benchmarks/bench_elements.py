"""Element modelling: accuracy against cost — SPEC §1 (G §3.1.1, eq. 5–6).

1. Resolution sweep (32…256 cells along the grain) for the three distance routes (exact,
   euclidean, manhattan = G eq. 5): time per grain (warm, whole chain scatter → remesh, P = 1) and
   the remeshed surface against the exact surface of base mesh ∪ spheres: two-sided Hausdorff and
   mean distance (in grain lengths and in voxels), volume error, triangle count; and the offset
   surface at level −2 voxels (grown by two cells) against the exact offset: mean |SDF − level| of
   its vertices in voxels (one-sided), where the metric of eq. 5 matters.
2. Expansion P (G eq. 6) at the default resolution: the ``expand`` node scales the field exactly (the
   grid with it, so the voxels grow by P in mm) against re-voxelising the swollen grain at the unswollen
   voxel size (P³ the cells): time per grain, surface error in mm and in swollen-grain lengths, volume
   error against P³ × the exact volume.
3. Remesh triangle budget (``remesh.target_faces``) at the default resolution: time of the remesh
   (marching cubes + quadric decimation), triangles, surface and volume error of the decimated grain.
4. The issue's target: 16 japonica grains at the default resolution, as the recipe builds them.
5. Peak memory (resident set of a child process) of one element at resolution 256.

Run: ``python benchmarks/bench_elements.py`` (``--quick`` for a smoke run). Writes
``benchmarks/results/bench_elements.{md,png}``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit, prange

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from nodes.elements import base_mesh, distance_field, expand, remesh, sphere_scatter, voxelise
from nodes.elements.level_set_mesh import grain_surface
from nodes.elements.sphere_sampling import surface_points
from nodes.elements.voxel_grid import Grid, mesh_occupancy, sphere_field
from nodes.mesh_inside import inside_points
from nodes.triangle_distance import point_triangle_offset

RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or Path(__file__).parent / "results")
RESOLUTIONS = (32, 48, 64, 96, 128, 192, 256)
OFFSET_VOXELS = -2.0
METHODS = ("exact", "euclidean", "manhattan")


@njit(parallel=True, cache=True)
def distance_to_faces(points, vertices, faces, candidates):
    """Distance from each point to its candidate faces (row of face indices, −1 = none); all if empty."""
    out = np.empty(points.shape[0])
    for p in prange(points.shape[0]):
        best = np.inf
        count = candidates.shape[1] if candidates.shape[0] else faces.shape[0]
        for c in range(count):
            f = candidates[p, c] if candidates.shape[0] else c
            if f < 0:
                continue
            ex, ey, ez = point_triangle_offset(
                points[p, 0],
                points[p, 1],
                points[p, 2],
                vertices[faces[f, 0]],
                vertices[faces[f, 1]],
                vertices[faces[f, 2]],
            )
            d2 = ex * ex + ey * ey + ez * ez
            if d2 < best:
                best = d2
        out[p] = np.sqrt(best)
    return out


class ExactGrain:
    """The exact solid base mesh ∪ spheres: signed distance at points, surface samples, volume."""

    def __init__(self, mesh, spheres, rng):
        self.vertices, self.faces = mesh.vertices, mesh.faces
        self.centers, self.radii = spheres.centers, spheres.radii
        self.rng = rng

    def signed_distance(self, points):
        """max(mesh, spheres) signed distance (exact outside the solid, a lower bound just inside)."""
        none = np.empty((0, 1), np.int64)
        d_mesh = distance_to_faces(points, self.vertices, self.faces, none)
        d_mesh = np.where(inside_points(self.vertices, self.faces, points), d_mesh, -d_mesh)
        d_sph = (self.radii - np.linalg.norm(points[:, None] - self.centers[None], axis=2)).max(axis=1)
        return np.maximum(d_mesh, d_sph)

    def surface_samples(self, count):
        """Points on the boundary of the union: mesh samples outside every sphere, sphere samples outside the rest."""
        on_mesh = surface_points(self.vertices, self.faces, count, self.rng)[0]
        keep = (np.linalg.norm(on_mesh[:, None] - self.centers[None], axis=2) > self.radii).all(axis=1)
        samples = [on_mesh[keep]]
        area = self.radii**2
        per = np.maximum((count * area / area.sum()).astype(int), 8)
        for c, r, n in zip(self.centers, self.radii, per):
            d = self.rng.normal(size=(n, 3))
            p = c + r * d / np.linalg.norm(d, axis=1, keepdims=True)
            others = np.linalg.norm(p[:, None] - self.centers[None], axis=2) < self.radii - 1e-12
            outside = ~others.any(axis=1) & ~inside_points(self.vertices, self.faces, p)
            samples.append(p[outside])
        return np.concatenate(samples)

    def volume(self, resolution=400):
        """Volume by counting cell centres of a randomly shifted fine grid (stratified sampling)."""
        lo = np.minimum(self.vertices.min(0), (self.centers - self.radii[:, None]).min(0))
        hi = np.maximum(self.vertices.max(0), (self.centers + self.radii[:, None]).max(0))
        h = float((hi - lo).max()) / resolution
        shape = tuple(int(n) for n in np.ceil((hi - lo) / h) + 2)
        grid = Grid(lo - h + self.rng.uniform(0, h, 3), h, shape)
        inside = mesh_occupancy(grid, self.vertices, self.faces) | (
            sphere_field(grid, self.centers, self.radii, 1.0) > 0
        )
        return inside.sum() * h**3


def surface_errors(exact: ExactGrain, vertices, faces, samples):
    """Two-sided Hausdorff and mean distance between the remeshed and the exact surface (mm)."""
    import trimesh
    from scipy.spatial import cKDTree

    forward = np.abs(exact.signed_distance(vertices))
    vertex_faces = trimesh.Trimesh(vertices, faces, process=False).vertex_faces
    _, near = cKDTree(vertices).query(samples, k=6)
    candidates = vertex_faces[near].reshape(len(samples), -1)
    backward = distance_to_faces(samples, vertices, faces, np.ascontiguousarray(candidates, np.int64))
    hausdorff = max(forward.max(), backward.max())
    mean = 0.5 * (forward.mean() + backward.mean())
    return hausdorff, mean


def grain_chain(mesh, seed, resolution, method, target_faces=None, expansion=(1.0, 1.0)):
    """The recipe's chain for one grain; returns every intermediate value and the wall time."""
    t0 = time.perf_counter()
    spheres = sphere_scatter.call(seed=seed, mesh=mesh)
    volume = voxelise.call(mesh=mesh, spheres=spheres, resolution=resolution)
    field = distance_field.call(volume=volume, mesh=mesh, spheres=spheres, method=method)
    grown = expand.call(seed=seed, field=field, expansion=expansion)
    grain = remesh.call(field=grown, target_faces=target_faces)
    return spheres, volume, field, grain, time.perf_counter() - t0


def sweep(resolutions, grains, samples):
    import trimesh

    mesh = base_mesh.call()
    length = float(np.ptp(mesh.vertices[:, 0]))
    grain_chain(mesh, 0, 32, "exact")  # warm JIT and imports
    rows = []
    references = {}
    for resolution in resolutions:
        for method in METHODS:
            times, haus, mean, mean_vox, vol_err, tris, offset = [], [], [], [], [], [], []
            for seed in range(grains):
                spheres, volume, field, grain, seconds = grain_chain(mesh, seed, resolution, method)
                times.append(seconds)
                if seed not in references:
                    exact = ExactGrain(mesh, spheres, np.random.default_rng(seed))
                    references[seed] = (exact, exact.surface_samples(samples), exact.volume())
                exact, points, true_volume = references[seed]
                v, f = grain_surface(np.asarray(field.data), field.origin, field.voxel_size, 0.0, 0, None)
                h, m = surface_errors(exact, v, f, points)
                haus.append(h / length)
                mean.append(m / length)
                mean_vox.append(m / field.voxel_size)
                vol_err.append(trimesh.Trimesh(v, f, process=False).volume / true_volume - 1.0)
                tris.append(len(grain.faces))
                level = OFFSET_VOXELS * field.voxel_size
                v, f = grain_surface(np.asarray(field.data), field.origin, field.voxel_size, level, 0, None)
                offset.append(np.abs(exact.signed_distance(v) - level).mean() / field.voxel_size)
            rows.append(
                {
                    "resolution": resolution,
                    "method": method,
                    "grid": "×".join(map(str, volume.data.shape)),
                    "ms_per_grain": 1e3 * float(np.median(times)),
                    "hausdorff": float(np.mean(haus)),
                    "mean": float(np.mean(mean)),
                    "mean_voxels": float(np.mean(mean_vox)),
                    "volume_error": float(np.mean(vol_err)),
                    "triangles": int(np.mean(tris)),
                    "offset_voxels": float(np.mean(offset)),
                }
            )
            r = rows[-1]
            print(
                f"{resolution:4d} {method:9s} {r['grid']:>12s} {r['ms_per_grain']:8.1f} ms  "
                f"H {100 * r['hausdorff']:6.3f} %  mean {100 * r['mean']:6.3f} % ({r['mean_voxels']:.3f} vox)  "
                f"vol {100 * r['volume_error']:+6.2f} %  {r['triangles']} tris  offset {r['offset_voxels']:.3f} vox",
                flush=True,
            )
    return rows, length


class ScaledGrain(ExactGrain):
    """The exact solid of ``grain`` scaled by ``p`` about ``centre`` (G eq. 6 applied to the exact surface)."""

    def __init__(self, grain: ExactGrain, p: float, centre):
        self.vertices = centre + p * (grain.vertices - centre)
        self.faces = grain.faces
        self.centers, self.radii = centre + p * (grain.centers - centre), p * grain.radii
        self.rng = grain.rng


def swelling_centre(field) -> np.ndarray:
    """The centre ``expand`` scales about: the occupied cells' centroid (level_set_mesh.expand_field)."""
    inside = np.argwhere(np.asarray(field.data) > 0)
    return np.asarray(field.origin) + inside.mean(axis=0) * field.voxel_size


def expansion_sweep(resolution, expansions, grains, samples):
    """G eq. 6 two ways at each P: ``expand`` on the field (the node) or re-voxelise the swollen grain.

    The node scales grid and distances together (no resampling), so its error relative to the grain is
    that of P = 1 while its voxels, and its error in mm, grow by P; holding the voxel size in mm instead
    means re-voxelising the swollen solid: ≈ P³ the cells. Both against the exact swollen solid; the time
    is the whole chain from the scatter on.
    """
    from nodegraph.values import Mesh
    from nodes.values import SphereSet

    mesh = base_mesh.call()
    warm = grain_chain(mesh, 0, resolution, "exact")[0]  # imports and kernels compiled before any timing
    voxelise.call(mesh=mesh, spheres=warm, voxel_size=0.2)
    found: dict[tuple[float, str], list] = {}
    for p in expansions:
        for seed in range(grains):
            rng = np.random.default_rng(seed)
            t0 = time.perf_counter()
            spheres = sphere_scatter.call(seed=seed, mesh=mesh)
            volume = voxelise.call(mesh=mesh, spheres=spheres, resolution=resolution)
            field = distance_field.call(volume=volume, mesh=mesh, spheres=spheres, method="exact")
            grown = expand.call(field=field, expansion=(p, p))
            v, f = grain_surface(np.asarray(grown.data), grown.origin, grown.voxel_size, 0.0, 0, None)
            seconds = time.perf_counter() - t0
            exact = ScaledGrain(ExactGrain(mesh, spheres, rng), p, swelling_centre(field))
            found.setdefault((p, "expand"), []).append((seconds, grown, v, f, exact))

            t0 = time.perf_counter()
            spheres = sphere_scatter.call(seed=seed, mesh=mesh)
            exact = ScaledGrain(ExactGrain(mesh, spheres, rng), p, mesh.vertices.mean(axis=0))
            swollen, balls = Mesh(exact.vertices, exact.faces), SphereSet(exact.centers, exact.radii)
            volume = voxelise.call(mesh=swollen, spheres=balls, voxel_size=field.voxel_size)
            grown = distance_field.call(volume=volume, mesh=swollen, spheres=balls, method="exact")
            v, f = grain_surface(np.asarray(grown.data), grown.origin, grown.voxel_size, 0.0, 0, None)
            seconds = time.perf_counter() - t0
            found.setdefault((p, "re-voxelise"), []).append((seconds, grown, v, f, exact))
    rows = []
    for (p, route), runs in found.items():
        haus, mean, haus_l, vol_err = [], [], [], []
        for _, _, v, f, exact in runs:
            h, m = surface_errors(exact, v, f, exact.surface_samples(samples))
            haus.append(h)
            mean.append(m)
            haus_l.append(h / float(np.ptp(exact.vertices[:, 0])))
            vol_err.append(trimesh_volume(v, f) / exact.volume() - 1.0)
        grown = runs[0][1]
        rows.append(
            {
                "P": p,
                "route": route,
                "grid": "×".join(map(str, np.asarray(grown.data).shape)),
                "voxel_mm": float(grown.voxel_size),
                "ms_per_grain": 1e3 * float(np.median([r[0] for r in runs])),
                "hausdorff_mm": float(np.mean(haus)),
                "mean_mm": float(np.mean(mean)),
                "hausdorff_L": float(np.mean(haus_l)),
                "volume_error": float(np.mean(vol_err)),
                "triangles": int(np.mean([len(r[3]) for r in runs])),
            }
        )
        r = rows[-1]
        print(
            f"P {p:.2f} {route:11s} {r['grid']:>12s} {r['ms_per_grain']:8.1f} ms  H {r['hausdorff_mm']:.4f} mm "
            f"mean {r['mean_mm']:.4f} mm  vol {100 * r['volume_error']:+.2f} %",
            flush=True,
        )
    return rows


def trimesh_volume(vertices, faces) -> float:
    import trimesh

    return float(trimesh.Trimesh(vertices, faces, process=False).volume)


def remesh_sweep(resolution, budgets, grains, samples):
    """``remesh.target_faces``: the remesh's time (marching cubes + decimation) and the decimated grain's error."""
    mesh = base_mesh.call()
    length = float(np.ptp(mesh.vertices[:, 0]))
    fields = []
    for seed in range(grains):
        spheres, _, field, _, _ = grain_chain(mesh, seed, resolution, "exact")
        exact = ExactGrain(mesh, spheres, np.random.default_rng(seed))
        fields.append((field, exact, exact.surface_samples(samples), exact.volume()))
    rows = []
    for budget in budgets:
        times, haus, mean, vol_err, tris, verts = [], [], [], [], [], []
        for field, exact, points, true_volume in fields:
            t0 = time.perf_counter()
            v, f = grain_surface(np.asarray(field.data), field.origin, field.voxel_size, 0.0, 0, budget)
            times.append(time.perf_counter() - t0)
            h, m = surface_errors(exact, v, f, points)
            haus.append(h / length)
            mean.append(m / length)
            vol_err.append(trimesh_volume(v, f) / true_volume - 1.0)
            tris.append(len(f))
            verts.append(len(v))
        rows.append(
            {
                "target_faces": budget,
                "vertices": int(np.mean(verts)),
                "triangles": int(np.mean(tris)),
                "ms_remesh": 1e3 * float(np.median(times)),
                "hausdorff": float(np.mean(haus)),
                "mean": float(np.mean(mean)),
                "volume_error": float(np.mean(vol_err)),
            }
        )
        r = rows[-1]
        print(
            f"target_faces {budget!s:>6s}: {r['triangles']:6d} tris {r['ms_remesh']:7.1f} ms  "
            f"H {100 * r['hausdorff']:.3f} %  mean {100 * r['mean']:.3f} %  vol {100 * r['volume_error']:+.2f} %",
            flush=True,
        )
    return rows


def sixteen_grains(resolution, repeats):
    """16 japonica grains as graphs/rice_grains.yaml builds them (exact route, P = 1.5, 2000 faces)."""
    mesh = base_mesh.call()
    out = {}
    for label, target in (("no budget", None), ("target_faces 2000", 2000)):
        grain_chain(mesh, 99, resolution, "exact", target, (1.5, 1.5))  # warm
        best = np.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            for seed in range(16):
                grain_chain(mesh, seed, resolution, "exact", target, (1.5, 1.5))
            best = min(best, time.perf_counter() - t0)
        out[label] = best
        print(f"16 grains at resolution {resolution} ({label}): {best:.3f} s (best of {repeats})", flush=True)
    return out


def peak_rss_mib() -> float:
    """This process's peak resident set (VmHWM). Not ru_maxrss: that survives exec from the parent."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def memory_child(resolution: int, shape: str, method: str) -> None:
    """Run one element at ``resolution`` and print its peak resident set (MiB) as JSON."""
    mesh = base_mesh.call(shape=shape)
    t0 = time.perf_counter()
    spheres, volume, field, grain, _ = grain_chain(mesh, 0, resolution, method)
    seconds = time.perf_counter() - t0
    print(
        json.dumps(
            {
                "peak_mib": peak_rss_mib(),
                "grid": list(volume.data.shape),
                "seconds": seconds,
                "triangles": len(grain.faces),
            }
        )
    )


def baseline_child() -> None:
    """Peak resident set after imports and a tiny warm run: subtract to get what an element adds."""
    mesh = base_mesh.call()
    grain_chain(mesh, 0, 32, "exact")
    print(json.dumps({"peak_mib": peak_rss_mib()}))


def measure_memory(resolution, configs=(("rice", "exact"), ("rice", "euclidean"), ("ikura", "exact"))):
    rows = []
    script = str(Path(__file__).resolve())
    base = json.loads(
        subprocess.run([sys.executable, script, "--baseline-child"], capture_output=True, text=True, check=True)
        .stdout.strip()
        .splitlines()[-1]
    )["peak_mib"]
    for shape, method in configs:
        run = subprocess.run(
            [sys.executable, script, "--memory-child", str(resolution), shape, method],
            capture_output=True,
            text=True,
            check=True,
        )
        r = json.loads(run.stdout.strip().splitlines()[-1])
        r.update(shape=shape, method=method, baseline_mib=base)
        rows.append(r)
        print(
            f"resolution {resolution} {shape} {method}: grid {'×'.join(map(str, r['grid']))}, peak RSS "
            f"{r['peak_mib']:.0f} MiB (imports + warm run alone: {base:.0f} MiB), {r['seconds']:.2f} s",
            flush=True,
        )
    return rows


def write_results(rows, length, sixteen, memory, resolution, expansion, budgets, knob_resolution):
    RESULTS.mkdir(parents=True, exist_ok=True)
    lines = [
        f"Grain: japonica base 5 × 3 × 2 mm + 40 spheres r ∈ [0.2, 0.5] mm (length L = {length:.2f} mm), "
        "P = 1; errors against the exact surface of mesh ∪ spheres, mean of the grains.",
        "",
        f"Offset: surface at level {OFFSET_VOXELS} voxels, mean |SDF − level| of its vertices (voxels).",
        "",
        "| res | method | grid | ms/grain | Hausdorff (L) | mean (L) | mean (voxels) | volume err | triangles "
        "| offset mean (voxels) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['resolution']} | {r['method']} | {r['grid']} | {r['ms_per_grain']:.1f} | "
            f"{100 * r['hausdorff']:.3f} % | {100 * r['mean']:.3f} % | {r['mean_voxels']:.3f} | "
            f"{100 * r['volume_error']:+.2f} % | {r['triangles']} | {r['offset_voxels']:.3f} |"
        )
    lines += [
        "",
        f"Expansion P (G eq. 6) at resolution {knob_resolution}, exact route: `expand` scales the field (voxels "
        "grow by P) or the swollen grain is re-voxelised at the unswollen voxel size; errors against the exact swollen "
        "solid (L = swollen grain length), time of the whole chain per grain.",
        "",
        "| P | route | grid | voxel (mm) | ms/grain | Hausdorff (mm) | mean (mm) | Hausdorff (L) | volume err "
        "| triangles |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {r['P']:g} | {r['route']} | {r['grid']} | {r['voxel_mm']:.4f} | {r['ms_per_grain']:.1f} | "
        f"{r['hausdorff_mm']:.4f} | {r['mean_mm']:.4f} | {100 * r['hausdorff_L']:.3f} % | "
        f"{100 * r['volume_error']:+.2f} % | {r['triangles']} |"
        for r in expansion
    ]
    lines += [
        "",
        f"Remesh triangle budget at resolution {knob_resolution}, exact route, P = 1: time of the remesh alone "
        "(marching cubes, outer shell, quadric decimation), error of the result against the exact surface; what "
        "every later node (shade, export, preview, measure) handles per element is its vertices.",
        "",
        "| target_faces | triangles | ms/grain remesh | Hausdorff (L) | mean (L) | volume err "
        "| vertices in a 2,000-grain scene |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {'none' if r['target_faces'] is None else r['target_faces']} | {r['triangles']} | {r['ms_remesh']:.1f} | "
        f"{100 * r['hausdorff']:.3f} % | {100 * r['mean']:.3f} % | {100 * r['volume_error']:+.2f} % | "
        f"{2000 * r['vertices'] / 1e6:.2f} M |"
        for r in budgets
    ]
    lines += ["", f"16 japonica grains, resolution {resolution}, exact route, P = 1.5 (best of repeats, warm):", ""]
    lines += [f"- {label}: {seconds:.3f} s ({1e3 * seconds / 16:.0f} ms/grain)" for label, seconds in sixteen.items()]
    lines += ["", "Peak resident memory of one element (child process):", ""]
    lines += [
        f"- {m['shape']} {m['method']}, grid {'×'.join(map(str, m['grid']))}: {m['peak_mib']:.0f} MiB "
        f"(imports + warm-up alone {m['baseline_mib']:.0f} MiB), {m['seconds']:.2f} s"
        for m in memory
    ]
    (RESULTS / "bench_elements.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    for method in METHODS:
        sel = [r for r in rows if r["method"] == method]
        res = [r["resolution"] for r in sel]
        axes[0].plot(res, [r["ms_per_grain"] for r in sel], "o-", label=method)
        axes[1].plot(res, [100 * r["mean"] for r in sel], "o-", label=f"{method} mean")
        axes[1].plot(res, [100 * r["hausdorff"] for r in sel], "x--", label=f"{method} Hausdorff")
        axes[2].plot(res, [100 * abs(r["volume_error"]) for r in sel], "o-", label=method)
    axes[0].set(
        xlabel="resolution (cells along the grain)", ylabel="ms per grain", yscale="log", title="time per grain (warm)"
    )
    axes[1].set(xlabel="resolution", ylabel="% of grain length", yscale="log", title="surface error")
    axes[2].set(xlabel="resolution", ylabel="|volume error| %", yscale="log", title="volume error")
    for ax in axes:
        ax.axvline(resolution, color="grey", lw=0.8)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(RESULTS / "bench_elements.png", dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    for route, marker in (("expand", "o-"), ("re-voxelise", "s--")):
        sel = [r for r in expansion if r["route"] == route]
        axes[0].plot([r["ms_per_grain"] for r in sel], [r["mean_mm"] for r in sel], marker, label=route)
        for r in sel:
            axes[0].annotate(f"P {r['P']:g}", (r["ms_per_grain"], r["mean_mm"]), fontsize=7, xytext=(3, 3),
                             textcoords="offset points")  # fmt: skip
    axes[0].set(xlabel="ms per grain", ylabel="mean surface error (mm)", title="expansion P: two routes")
    axes[1].plot([r["ms_remesh"] for r in budgets], [100 * r["hausdorff"] for r in budgets], "o-", label="Hausdorff")
    axes[1].plot([r["ms_remesh"] for r in budgets], [100 * r["mean"] for r in budgets], "s-", label="mean")
    for r in budgets:
        axes[1].annotate(f"{r['triangles']}", (r["ms_remesh"], 100 * r["hausdorff"]), fontsize=7, xytext=(3, 3),
                         textcoords="offset points")  # fmt: skip
    axes[1].set(xlabel="ms per grain (remesh)", ylabel="% of grain length", yscale="log",
                title="remesh target_faces (labels: triangles)")  # fmt: skip
    for ax in axes:
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(RESULTS / "bench_elements_knobs.png", dpi=110)
    print(f"wrote {RESULTS / 'bench_elements.md'} and {RESULTS / 'bench_elements.png'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="two resolutions, one grain: a smoke run")
    parser.add_argument("--memory-child", nargs=3, metavar=("RES", "SHAPE", "METHOD"), help=argparse.SUPPRESS)
    parser.add_argument("--baseline-child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--memory", type=int, metavar="RES", help="only the peak-memory measurement at RES")
    parser.add_argument(
        "--knobs", action="store_true", help="only the sweeps docs/accuracy.md reads (no 16-grain timing, no memory)"
    )
    args = parser.parse_args()
    if args.memory_child:
        memory_child(int(args.memory_child[0]), args.memory_child[1], args.memory_child[2])
        return
    if args.baseline_child:
        baseline_child()
        return
    if args.memory:
        measure_memory(args.memory)
        return
    from nodes.elements.voxelise import DEFAULT_RESOLUTION

    resolutions = (32, 64) if args.quick else RESOLUTIONS
    rows, length = sweep(resolutions, grains=1 if args.quick else 2, samples=2000 if args.quick else 10000)
    knob_resolution = 32 if args.quick else DEFAULT_RESOLUTION
    expansion = expansion_sweep(
        knob_resolution,
        (1.0, 1.5) if args.quick else (1.0, 1.2, 1.5, 2.0),
        grains=1 if args.quick else 2,
        samples=2000 if args.quick else 10000,
    )
    budgets = remesh_sweep(
        knob_resolution,
        (None, 1000, 250) if args.quick else (None, 8000, 4000, 1800, 1000, 500, 250),
        grains=1 if args.quick else 2,
        samples=2000 if args.quick else 10000,
    )
    sixteen = {} if args.knobs else sixteen_grains(DEFAULT_RESOLUTION, repeats=1 if args.quick else 3)
    memory = [] if args.knobs else measure_memory(64, (("rice", "exact"),)) if args.quick else measure_memory(256)
    write_results(rows, length, sixteen, memory, DEFAULT_RESOLUTION, expansion, budgets, knob_resolution)


if __name__ == "__main__":
    main()
