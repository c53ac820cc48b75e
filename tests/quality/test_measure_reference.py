"""measure, its libigl calls grouped into tasks, gives the very floats of the measure it replaced (kept below as the
reference)."""

from __future__ import annotations

import numpy as np
import trimesh

from nodegraph.values import Mesh
from nodes.quality import measure
from nodes.values import Aggregate, ElementLibrary, Placement


def reference_measure(aggregates, seed, sample=300, contact=0.02) -> dict[str, float]:
    """The ``measure`` node before issue 27's rework (main 6b2699b), verbatim but for the vessel column: one
    process, an element at a time, one libigl call per neighbour mesh."""
    import igl
    from scipy.spatial import cKDTree

    from nodes.quality.mesh_overlap import outer_shell, volume

    meshes, centres, radii, volumes, lows, tops = [], [], [], [], [], []
    for aggregate in aggregates:
        p = aggregate.placement
        shapes = aggregate.without_normals()
        shells, lengths = {}, {}
        for i in range(len(p)):
            mesh = shapes.element_mesh(i)
            key = (int(p.kinds[i]), int(p.variants[i]) % len(aggregate.libraries[p.kinds[i]]))
            if key not in shells:
                shells[key] = outer_shell(mesh.faces, mesh.parts)
                own = aggregate.libraries[key[0]].meshes[key[1]]
                lengths[key] = float(np.ptp(own.vertices, axis=0).max())
            used, faces = shells[key]
            vertices = mesh.vertices if used is None else mesh.vertices[used]
            lo, hi = vertices.min(axis=0), vertices.max(axis=0)
            centre = 0.5 * (lo + hi)
            meshes.append((vertices, faces, lengths[key]))
            centres.append(centre)
            radii.append(float(np.linalg.norm(vertices - centre, axis=1).max()))
            volumes.append(abs(volume(vertices, faces)))
            lows.append(lo[2])
            tops.append(hi[2])
    n = len(meshes)
    picked = np.sort(np.random.default_rng(seed).choice(n, size=min(sample, n), replace=False))
    centres, radii = np.array(centres), np.array(radii)
    # element_overlaps
    tree = cKDTree(centres)
    longest = max(length for _, _, length in meshes)
    reach = 2.0 * float(radii.max()) + contact * longest
    pairs, boxes = [], {}
    for row, i in enumerate(picked):
        vertices, _, length = meshes[i]
        margin = contact * length
        for j in tree.query_ball_point(centres[i], reach):
            if j == i or np.linalg.norm(centres[j] - centres[i]) > radii[i] + radii[j] + margin:
                continue
            if j not in boxes:
                boxes[j] = meshes[j][0].min(axis=0), meshes[j][0].max(axis=0)
            lo, hi = boxes[j]
            near = np.all((vertices >= lo - margin) & (vertices <= hi + margin), 1)
            if near.any():
                pairs.append((row, j, vertices[near]))
    by_neighbour: dict[int, list[int]] = {}
    for k, (_, j, _) in enumerate(pairs):
        by_neighbour.setdefault(j, []).append(k)
    closest = np.empty(len(pairs))
    for j, ks in by_neighbour.items():
        other_v, other_f, _ = meshes[j]
        points = np.concatenate([pairs[k][2] for k in ks])
        signed = igl.signed_distance(points, other_v, other_f, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER)[
            0
        ]
        starts = np.cumsum([0] + [len(pairs[k][2]) for k in ks[:-1]])
        closest[ks] = np.minimum.reduceat(signed, starts)
    depths, contacts = [], np.zeros(len(picked), np.int64)
    for (row, _, _), nearest in zip(pairs, closest.tolist()):
        length = meshes[picked[row]][2]
        if nearest < contact * length:
            contacts[row] += 1
            depths.append(max(0.0, -nearest) / length)
    points = np.concatenate([m[0] for m in meshes])
    hull = trimesh.convex.convex_hull(points[:: max(1, len(points) // 200_000)]).volume
    depth = np.array(depths) if depths else np.zeros(1)
    return {
        "elements": n,
        "sampled": len(picked),
        "overlap_p50": np.percentile(depth, 50),
        "overlap_p95": np.percentile(depth, 95),
        "overlap_max": depth.max(),
        "touching_pairs": len(depths),
        "deeper_than_1pct": np.mean(depth > 0.01),
        "contacts_per_element": contacts.mean(),
        "packing_fraction": sum(volumes) / hull,
        "fill_height": np.percentile(tops, 95) - min(lows),
        "skin": np.mean([reference_skin(meshes[i][0], meshes[i][1]) for i in picked]),
    }


def reference_skin(vertices, faces) -> float:
    """``skin_score`` before its topology was shared per library mesh (main 6b2699b)."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    normals = np.cross(b - a, c - a)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    start = faces.ravel()
    end = np.roll(faces, -1, axis=1).ravel()
    opposite = np.roll(faces, -2, axis=1).ravel()
    owner = np.repeat(np.arange(len(faces)), 3)
    lo, hi = np.minimum(start, end), np.maximum(start, end)
    key = lo * len(vertices) + hi
    order = np.argsort(key, kind="stable")
    key = key[order]
    pair = np.flatnonzero(key[1:] == key[:-1])
    first, second = order[pair], order[pair + 1]
    f1, f2 = owner[first], owner[second]
    length = np.linalg.norm(vertices[end[first]] - vertices[start[first]], axis=1)
    cosine = np.clip(np.einsum("ij,ij->i", normals[f1], normals[f2]), -1.0, 1.0)
    angle = np.arccos(cosine)
    rise = np.einsum("ij,ij->i", vertices[opposite[second]] - vertices[start[first]], normals[f1])
    weight = length * angle
    total = weight.sum()
    return float(weight[rise > 0.0].sum() / total) if total > 0.0 else 0.0


def lumpy(rng, axes, bumps=0.06) -> trimesh.Trimesh:
    sphere = trimesh.creation.icosphere(3)
    unit = sphere.vertices
    radius = 1.0 + bumps * np.sin(5 * unit[:, 0] + rng.uniform(0, 6)) * np.sin(4 * unit[:, 1])
    return trimesh.Trimesh(unit * radius[:, None] * axes, sphere.faces, process=False)


def pile(seed: int = 7) -> list[Aggregate]:
    """Two aggregates packed into each other: bumpy grains of three variants (deformed, some bent) on a jittered
    grid closer than their size, and two-part eggs (a yolk inside: not a neighbour) among them."""
    rng = np.random.default_rng(seed)
    grains = ElementLibrary(
        "grain", tuple(Mesh(m.vertices, m.faces, name="grain") for m in (lumpy(rng, [2.5, 1.5, 1.0]) for _ in range(3)))
    )
    shell, yolk = trimesh.creation.icosphere(2), trimesh.creation.icosphere(1)
    egg = Mesh(
        np.vstack([shell.vertices * 1.6, yolk.vertices * 0.7]),
        np.vstack([shell.faces, yolk.faces + len(shell.vertices)]),
        parts=np.r_[np.zeros(len(shell.faces)), np.ones(len(yolk.faces))],
        name="egg",
    )
    grid = np.stack(np.meshgrid(np.arange(6), np.arange(5), np.arange(4), indexing="ij"), -1).reshape(-1, 3)
    positions = grid * [2.6, 2.2, 1.7] + rng.normal(0.0, 0.15, (len(grid), 3))
    rotations = np.array([trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3] for _ in grid])
    deformations = np.eye(3) + rng.normal(0.0, 0.03, (len(grid), 3, 3))
    bends = rng.normal(0.0, 0.01, (len(grid), 3, 6))
    bends[::2] = 0.0
    placed = Placement(
        positions, np.tile([0.0, 0.0, 1.0], (len(grid), 1)), rotations, variants=rng.integers(0, 3, len(grid))
    )
    eggs = Placement(rng.uniform([0, 0, 0], [13, 9, 5], (12, 3)), np.tile([0.0, 0.0, 1.0], (12, 1)))
    return [
        Aggregate(placed, (grains,), deformations=deformations, bends=bends),
        Aggregate(eggs, (ElementLibrary("egg", (egg,)),)),
    ]


def test_measure_gives_the_floats_of_the_serial_reference():
    aggregates = pile()
    table = measure.call(seed=5, aggregates=aggregates, sample=60)
    expected = reference_measure(aggregates, seed=5, sample=60)
    assert expected["touching_pairs"] > 100 and expected["overlap_max"] > 0.05  # deep overlaps: not vacuous
    assert expected["skin"] > 0.0
    got = {name: table.columns[name][0].item() for name in expected}
    assert got == {name: float(value) if isinstance(value, np.floating) else value for name, value in expected.items()}


def test_a_sample_of_all_elements_in_many_tasks():
    """Every element sampled, eight libigl tasks and more: still the reference's floats."""
    aggregates = pile(seed=11)
    table = measure.call(seed=2, aggregates=aggregates, sample=1000)
    expected = reference_measure(aggregates, seed=2, sample=1000)
    assert expected["sampled"] == 132
    assert {name: table.columns[name][0].item() for name in expected} == {
        name: float(value) if isinstance(value, np.floating) else value for name, value in expected.items()
    }


def test_measure_forks_no_process_even_with_free_cores(monkeypatch):
    """No fork of a running process (nodegraph/runtime.py): a fork copies the forking thread alone, and OpenBLAS's
    fork handler stopped its workers under another thread's matrix product (a run hung: 8feda45). measure forked
    children for its libigl calls when ``FreeCores`` found a free core; it failed here then."""
    import os

    from nodes.simulation import threads

    class Free:
        def __init__(self, most):
            self.most = most

        def threads(self):
            return 2

    def no_fork():
        raise RuntimeError("measure forked a process")

    monkeypatch.setattr(threads, "FreeCores", Free)
    monkeypatch.setattr(os, "fork", no_fork)
    aggregates = pile(seed=11)
    table = measure.call(seed=2, aggregates=aggregates, sample=1000)  # 132 sampled: the old code forked from 16 tasks
    assert table.columns["sampled"][0] == 132
