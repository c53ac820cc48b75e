"""Particle clusters: how well the spheres cover each element's surface, and what building them costs —
SPEC §3 (G: the simulated proxy), issue 17.

Per element mesh and particle count: the gap of each shell vertex to the union of the cluster's spheres,
gap(v) = min_k(|v − c_k| − r_k) (> 0: outside every sphere; meshes whose spheres merely touch cut into
each other by up to that much), in element lengths L: max, p95, p50 (means over the meshes); how far a
sphere reaches beyond the mesh (exact distance to the surface; > 0 means grains look apart); how many
clusters the quadratic goal can observe (``shape_matching.quadratic_moments``); CPU seconds per mesh.
Rows ``quadratic=False``: the full cover a linear run could get.

Meshes: the rice_bowl recipe's element library (16 variants, ≈ 900 vertices); ``--quick``: four
ellipsoids 5 × 3 × 2…2.6 mm (642 vertices). ``--against PATH``: the same table for another
``clusters.py`` (e.g. a checkout of main), timed side by side in the same process.

Run: ``python benchmarks/bench_clusters.py [--quick] [--counts 8 12 16] [--against PATH]``.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from nodes.simulation.clusters import element_cluster
from nodes.simulation.shape_matching import quadratic_moments


def ellipsoids():
    import trimesh

    from nodegraph.values import Mesh

    sphere = trimesh.creation.icosphere(subdivisions=3)
    return [
        Mesh.from_trimesh(trimesh.Trimesh(sphere.vertices * [2.5, 1.5, h / 2], sphere.faces), name=f"e{h}")
        for h in (2.0, 2.2, 2.4, 2.6)
    ]


def rice_library():
    import yaml

    from nodegraph.api import Cache, default_registry, run_recipe
    from nodegraph.recipe import parse_recipe

    root = Path(__file__).resolve().parents[1]
    raw = yaml.safe_load((root / "graphs" / "rice_bowl.yaml").read_text())
    raw["outputs"] = ["rice.library"]
    recipe = parse_recipe(yaml.safe_dump(raw), default_registry(), "rice_bowl.yaml", [])
    with tempfile.TemporaryDirectory() as tmp:
        result = run_recipe(recipe, cache=Cache(Path(tmp) / "cache"), out_dir=Path(tmp) / "out")
        return result.output("rice.library").meshes


def load_other(path: str):
    """``element_cluster`` of another clusters.py, imported inside this package (its relative imports)."""
    spec = importlib.util.spec_from_file_location("nodes.simulation._bench_other_clusters", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module.element_cluster


def observable(centres) -> bool:
    q = centres - centres.mean(axis=0)
    return bool(quadratic_moments(q, np.ones(len(q)), np.array([0, len(q)]))[2][0])


def measure(build, meshes, count):
    """(gap max, p95, p50 in L, worst reach beyond the mesh in L, observable clusters, CPU s per mesh)."""
    import igl

    rows, reach, seen, cpu = [], 0.0, 0, 0.0
    for mesh in meshes:
        start = time.process_time()
        cluster = build(mesh, count)
        cpu += time.process_time() - start
        vertices, faces = np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)
        length = float(np.ptp(vertices, axis=0).max())
        gap = (np.linalg.norm(vertices[:, None] - cluster.centres[None], axis=2) - cluster.radii).min(axis=1)
        rows.append((gap.max(), np.percentile(gap, 95), np.percentile(gap, 50)) / np.float64(length))
        inside = np.sqrt(igl.point_mesh_squared_distance(cluster.centres, vertices, faces)[0])
        reach = max(reach, float((cluster.radii - inside).max()) / length)
        seen += observable(cluster.centres)
    return (*np.mean(rows, axis=0), reach, seen, cpu / len(meshes))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="four ellipsoids, 8 particles (seconds)")
    parser.add_argument("--counts", type=int, nargs="+", default=None, help="particles per element")
    parser.add_argument("--against", default=None, help="another clusters.py to compare with, side by side")
    args = parser.parse_args(argv)
    meshes = ellipsoids() if args.quick else rice_library()
    counts = args.counts or ([8] if args.quick else [8, 12, 16])
    builders = [("new", element_cluster), ("quadratic=False", lambda m, c: element_cluster(m, c, quadratic=False))]
    if args.against:
        builders.insert(0, ("against", load_other(args.against)))
    for _, build in builders:  # compile the kernels outside the timings
        build(meshes[0], counts[0])
    print(f"{len(meshes)} meshes, {np.mean([len(m.vertices) for m in meshes]):.0f} vertices each")
    print("| particles | clusters | gap max / L | p95 | p50 | beyond mesh / L | observable | CPU s/mesh |")
    print("|---|---|---|---|---|---|---|---|")
    for count in counts:
        for name, build in builders:
            g_max, p95, p50, reach, seen, cpu = measure(build, meshes, count)
            print(
                f"| {count} | {name} | {g_max:.3f} | {p95:.3f} | {p50:.3f} | {reach:.4f} | "
                f"{seen}/{len(meshes)} | {cpu:.4f} |"
            )


if __name__ == "__main__":
    main()
