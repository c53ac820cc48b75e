"""The ``elastic_body`` node: a closed surface pulled at a patch, shape-matched per piece, torn — SPEC §5 (U).

Thin: parameters → ``BodySettings`` and a pull, ``body.ElasticBody`` runs the steps, outputs are typed
values: the final closed surface (a Mesh coloured by piece), the torn pieces as separate closed meshes
(a ShadedScene the ``export`` node writes as .glb / USD) and a per-frame history table. Effect
``tearing``: without it no break test runs (``calls['tear_check']`` stays 0) and the body only deforms
and springs back (U fig. 4.1).
"""

from __future__ import annotations

import numpy as np

from nodegraph.cost import Cost, estimated_by
from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh, Table

from ..values import Material, ShadedScene

EFFECTS = ("tearing",)
PIECE_COLOURS = np.array(
    [[230, 90, 40], [60, 140, 220], [90, 190, 90], [240, 200, 60], [170, 90, 200], [60, 200, 200], [200, 60, 120]],
    np.uint8,
)


def _check(params):
    problems = []
    direction = params.get("pull_direction", [0.0, 0.0, 1.0])
    if len(direction) != 3 or not np.linalg.norm(direction) > 0:
        problems.append(("pull_direction", "three numbers, not all zero"))
    if params.get("pull_frames", 0) > params.get("frames", 1):
        problems.append(("pull_frames", "at most 'frames'"))
    return problems


# one body (its vertices are simulated in a moment: 602 for 1,200 substeps in 0.05 CPU s once compiled)
@estimated_by(lambda q: Cost(elements=1))
@node(
    "elastic_body",
    inputs={"mesh": In(Mesh, "closed surface to simulate (instead of the 'shape' solid)", optional=True)},
    outputs={
        "mesh": Out(Mesh, "the surface at the last frame, openings capped; colours and parts: piece id"),
        "pieces": Out(ShadedScene, "each piece as its own closed mesh (for 'export': .glb / USD)"),
        "history": Out(
            Table, "per frame: pieces, tears, broken edges, openings, break tests run, energy, stretch, shape error"
        ),
    },
    params={
        "shape": Param(
            str, "cube", "solid used when no mesh is wired: cube surface or icosphere", choices=("cube", "sphere")
        ),
        "segments": Param(int, 10, "cube: segments per edge (U table 4.1: 10, 15, 20, 25)", range=(1, 200)),
        "subdivisions": Param(int, 3, "sphere: icosphere subdivisions", range=(0, 6)),
        "size": Param(float, 20.0, "cube edge or sphere diameter", range=(1e-3, 1e4), units="mm"),
        "mass": Param(float, 10.0, "mass of the body, shared equally by its vertices", range=(1e-6, 1e6), units="g"),
        "frames": Param(int, 120, "frames to simulate", range=(1, 100000), units="frames"),
        "dt": Param(float, 1 / 60, "frame duration", range=(1e-4, 1.0), units="s"),
        # 10 from bench_tearing's accuracy sweep (k = 6 block, k = 2e4, 60 fps, against 400 substeps): shape
        # error 1.2e-3 of the size, first tear within 0.3 ms; 5: 3.3e-3 and 1.4 ms; 1–2: k·Δt² > 1 clamps α
        # to 1, a stiffer material (errors 0.54 and 0.07, the tear 1.1 s and 0.38 s early)
        "substeps": Param(int, 10, "time steps per frame (U: one per frame; see the comment)", range=(1, 1000)),
        "stiffness": Param(
            float,
            2.0e4,
            "k of α = min(1, k·Δt²) (U eq. 3.16): the goal's pull per unit offset; with Δt > 1/√k α "
            "clamps at 1 (U's stable bound) and the body is stiffer than asked",
            range=(0.0, 1e9),
            units="1/s²",
        ),
        "linear_deformation": Param(float, 0.3, "β of U eq. 3.19 (0 = rigid goal)", range=(0.0, 1.0)),
        "deformation": Param(str, "linear", "goal of the β share (SPEC §5)", choices=("linear", "quadratic")),
        "rotation_iterations": Param(int, 4, "iterations of the rotation extraction (Müller 2016)", range=(1, 64)),
        "damping": Param(
            float, 5.0, "velocity decay rate (0: U's undamped integration)", range=(0.0, 1000.0), units="1/s"
        ),
        "pull_direction": Param(
            list[float], [0.0, 0.0, 1.0], "pull along this direction, at the vertex farthest along it"
        ),
        "pull_acceleration": Param(
            float, 2.0e5, "acceleration of the pulled vertices", range=(0.0, 1e9), units="mm/s²"
        ),
        "pull_radius": Param(
            float, 0.0, "pull every vertex within this rest distance of that vertex", range=(0.0, 1e4), units="mm"
        ),
        "pull_frames": Param(int, 30, "frames the pull lasts; then it lets go", range=(0, 100000), units="frames"),
        "release_on_tear": Param(bool, True, "let go of the pull at the first tear (pulled until it tears)"),
        "hold": Param(bool, False, "hold the patch on the opposite side (the same radius) in place"),
        "tear_threshold": Param(
            float, 3.0, "an edge breaks beyond this × its rest length (U §4.1: 3)", range=(1.01, 100.0)
        ),
        "tear_rule": Param(
            str,
            "vertex",
            "vertex: a vertex whose every edge is over the threshold loses its fan (U); edge: each edge "
            "over it breaks, cracks grow (U §4.3)",
            choices=("vertex", "edge"),
        ),
        "log_every": Param(
            int, 1, "log the mesh to Rerun every k frames (0 = never)", range=(0, 100000), units="frames"
        ),
    },
    effects=EFFECTS,
    check=_check,
)
def elastic_body(ctx, mesh=None, **params):
    """Shape matching with tearing — SPEC §5 (U): pull, deform, spring back; with effect ``tearing``, break
    edges over the threshold, split, re-cluster and cap, each piece then matching its own rest shape."""
    from .body import BodySettings, ElasticBody

    p = params
    problems = _check(p)
    if problems:
        raise ValueError("; ".join(f"{name}: {message}" for name, message in problems))
    vertices, faces = _surface(mesh, p)
    settings = BodySettings(
        h=p["dt"] / p["substeps"],
        stiffness=p["stiffness"],
        beta=p["linear_deformation"],
        quadratic=p["deformation"] == "quadratic",
        rotation_iterations=p["rotation_iterations"],
        damping=p["damping"],
        tearing=ctx.wants("tearing"),
        threshold=p["tear_threshold"],
        rule=p["tear_rule"],
    )
    accel, moving = pull_field(vertices, p["pull_direction"], p["pull_acceleration"], p["pull_radius"], p["hold"])
    body = ElasticBody(vertices, faces, p["mass"], settings, accel=accel, moving=moving)
    rows = []
    with ctx.progress(p["frames"], "frames") as bar:
        _log(ctx, body, 0, p["log_every"], p["substeps"])
        for frame in range(1, p["frames"] + 1):
            if frame == p["pull_frames"] + 1 or (p["release_on_tear"] and body.tears):
                body.accel[:] = 0.0
            for _ in range(p["substeps"]):
                body.step()
            rows.append(frame_row(body, frame, p["dt"], p["size"]))
            _log(ctx, body, frame, p["log_every"], p["substeps"])
            bar.advance()
    history = Table({k: np.array([r[k] for r in rows]) for k in rows[0]}, index="frame")
    if ctx.rerun.enabled:
        _log_history(ctx, history, p["substeps"])
    return {"mesh": final_mesh(body), "pieces": pieces_scene(body), "history": history}


def _surface(mesh, p):
    """(vertices, faces) of the wired mesh (merged, so split corners become shared vertices) or the solid."""
    if mesh is not None:
        tm = mesh.to_trimesh()
        tm.merge_vertices()
        return np.asarray(tm.vertices), np.asarray(tm.faces)
    if p["shape"] == "cube":
        from .surface_mesh import cube_surface

        return cube_surface(p["segments"], p["size"])
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=p["subdivisions"], radius=0.5 * p["size"])
    return np.asarray(sphere.vertices), np.asarray(sphere.faces)


def pull_field(vertices, direction, acceleration, radius, hold):
    """Per-vertex pull (n, 3) on the patch around the vertex farthest along ``direction`` and, with
    ``hold``, the moving flags that hold the opposite patch."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    along = vertices @ d
    patch = lambda i: np.linalg.norm(vertices - vertices[i], axis=1) <= radius  # noqa: E731
    accel = np.zeros_like(vertices)
    accel[patch(int(np.argmax(along)))] = acceleration * d
    moving = ~patch(int(np.argmin(along))) if hold else np.ones(len(vertices), bool)
    return accel, moving


def frame_row(body, frame, dt, size):
    """One history row: counts, U's discrete energy, kinetic energy, the worst edge stretch and the rms
    distance to the goals over ``size`` (how far from its rest shape the body is)."""
    m = body.mesh
    stretch = np.linalg.norm(body.x[m.origin] - body.x[m.dest], axis=1) / body.rest_length
    mass = 1.0 / body.inv_mass
    return {
        "frame": frame,
        "time": frame * dt,
        "pieces": body.n_clusters,
        "tears": body.tears,
        "broken_edges": body.broken_edges,
        "openings": len(body.loop_start) - 1,
        "tear_checks": body.calls["tear_check"],
        "energy": body.energy(),
        "kinetic": 0.5 * float((mass * (body.v * body.v).sum(1)).sum()),
        "max_stretch": float(stretch.max()),
        "shape_error": float(np.sqrt(((body.x - body.goals) ** 2).sum(1).mean())) / size,
    }


def _colours(cluster):
    return PIECE_COLOURS[cluster % len(PIECE_COLOURS)]


def final_mesh(body) -> Mesh:
    """The closed surface: vertex colours and face parts by piece."""
    vertices, faces, cluster = body.closed_surface()
    return Mesh(vertices, faces, colors=_colours(cluster), parts=cluster[faces[:, 0]], name="elastic_body")


def pieces_scene(body) -> ShadedScene:
    """Every piece as its own closed mesh, one soft material, for ``export``."""
    meshes = tuple(
        Mesh(v, f, colors=np.tile(_colours(np.array([i])), (len(v), 1)), name=f"piece/{i:04d}")
        for i, (v, f) in enumerate(body.pieces())
    )
    material = Material("elastic", base_color=(0.85, 0.35, 0.15), roughness=0.4, subsurface=0.3)
    return ShadedScene(meshes, (material,), np.zeros(len(meshes), np.int32))


def _log(ctx, body, frame, every, substeps):
    """The mesh at sim_step frame·substeps, coloured by cluster id; the openings' rims as red points."""
    if not ctx.rerun.enabled or not every or frame % every:
        return
    import rerun as rr

    vertices, faces, cluster = body.closed_surface()
    ctx.rerun.set_time("sim_step", frame * substeps)
    ctx.rerun.log("body", rr.Mesh3D(vertex_positions=vertices, triangle_indices=faces, vertex_colors=_colours(cluster)))
    rim = body.x[body.loop] if len(body.loop) else np.zeros((0, 3))
    ctx.rerun.log("tears", rr.Points3D(rim, colors=[255, 0, 0], radii=0.01 * float(np.ptp(body.x0, axis=0).max())))


def _log_history(ctx, history, substeps):
    import rerun as rr

    steps = history.columns["frame"] * substeps
    for name in ("pieces", "tears", "energy", "kinetic", "max_stretch", "shape_error"):
        ctx.rerun.send_columns(
            f"scalars/{name}",
            indexes=[rr.TimeColumn("sim_step", sequence=steps)],
            columns=rr.Scalars.columns(scalars=np.asarray(history.columns[name], float)),
        )
