"""U's stability claims (SPEC §5, U eq. 3.16–3.18) asserted over whole runs: any Δt in 1e-4 … 1,
collinear / planar / one-vertex clusters, tearing until every triangle is alone; no NaN, no energy
growth without external work, every piece closed after capping."""

import numpy as np
import pytest

from nodes.tearing.body import BodySettings, ElasticBody
from nodes.tearing.surface_mesh import cube_surface

TETRA = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])


def _closed(faces):
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    fwd = {tuple(e) for e in directed}
    return len(fwd) == len(directed) and all((b, a) in fwd for a, b in directed)


def _perturbed(vertices, faces, settings, seed=0, scale=0.1, spin=0.0):
    body = ElasticBody(vertices, faces, 1.0, settings)
    rng = np.random.default_rng(seed)
    body.x += rng.normal(0.0, scale, body.x.shape)
    body.v += spin * np.cross([0.0, 0.0, 1.0], body.x - body.x.mean(0))  # a spin: the rotation must follow
    return body


def _no_growth(energy, bound):
    """Bounded by ``bound``·E₀ and no trend: the second half of the run peaks no higher than the first."""
    half = len(energy) // 2
    return energy.max() <= bound * energy[0] + 1e-12 and energy[half:].max() <= energy[:half].max() * 1.001


def _run(body, steps):
    """Energies over the run (first = before any step) and the largest distance from the centroid seen."""
    energy, extent = [body.energy()], 0.0
    for _ in range(steps):
        body.step()
        assert np.all(np.isfinite(body.x)) and np.all(np.isfinite(body.v))
        energy.append(body.energy())
        extent = max(extent, float(np.abs(body.x - body.x.mean(0)).max()))
    return np.array(energy), extent


@pytest.mark.parametrize("h", [1e-4, 1e-3, 1e-2, 0.1, 1.0])
@pytest.mark.parametrize("stiffness", [1e2, 1e4, 1e9])  # α from 1e-6 … 1 (clamped at U's bound)
def test_rigid_goal_conserves_u_energy_at_any_step(h, stiffness):
    vertices, faces = cube_surface(4, 1.0)
    body = _perturbed(vertices, faces, BodySettings(h=h, stiffness=stiffness), spin=0.0)
    energy, extent = _run(body, 300)
    assert energy.max() <= energy[0] * (1 + 1e-6)  # spectral radius 1: no growth, every step
    assert energy.min() >= energy[0] * (1 - 1e-4)  # and no numerical damping (U: none)
    assert extent < 1.5  # the body stays where it was (unit cube, 0.1 noise)


@pytest.mark.parametrize("h", [1e-4, 1e-2, 1.0])
@pytest.mark.parametrize("quadratic", [False, True])
def test_deformable_goal_energy_stays_bounded(h, quadratic):
    vertices, faces = cube_surface(4, 1.0)
    body = _perturbed(vertices, faces, BodySettings(h=h, stiffness=1e4, beta=0.5, quadratic=quadratic))
    energy, extent = _run(body, 1000)
    assert _no_growth(energy, 1.25)  # β's volume-normalised fit makes U's invariant oscillate, not grow
    assert extent < 1.5


@pytest.mark.parametrize("shape", ["collinear", "planar"])
@pytest.mark.parametrize("beta", [0.0, 0.5])
def test_collinear_and_planar_clusters(shape, beta):
    """Singular A_qq (and A_pq): a closed 'tetrahedron' whose four vertices lie on a line or in a plane."""
    rest = {
        "collinear": np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]),
        "planar": np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]),
    }[shape]
    for h in (1e-4, 1e-2, 1.0):
        body = _perturbed(rest, TETRA, BodySettings(h=h, stiffness=1e4, beta=beta), scale=0.05, spin=0.5)
        energy, extent = _run(body, 2000)
        assert _no_growth(energy, 1.25) and extent < 3.0  # measured: ≤ 1.2 E₀ over 20,000 steps
        if h < 1e-2:
            continue  # α = 1e-4 per step: settling takes 1e4 steps; stability is what is asserted here
        body.settings = BodySettings(h=h, stiffness=1e4, beta=beta, damping=0.5 / h)  # damped: it settles
        for _ in range(400):
            body.step()
        edges = np.linalg.norm(body.x[TETRA] - body.x[np.roll(TETRA, 1, axis=1)], axis=2)
        rest_edges = np.linalg.norm(rest[TETRA] - rest[np.roll(TETRA, 1, axis=1)], axis=2)
        assert edges == pytest.approx(rest_edges, abs=0.02)  # back to its rest shape (one cluster: order kept)


def test_a_lone_vertex_moves_on_its_own():
    """A vertex in no face is a cluster of one: no shape, so it keeps its velocity and feels its pull."""
    vertices = np.vstack([cube_surface(2, 1.0)[0], [[5.0, 0.0, 0.0]]])
    faces = cube_surface(2, 1.0)[1]
    accel = np.zeros_like(vertices)
    accel[-1] = [0.0, 0.0, 10.0]
    h = 1e-2
    body = ElasticBody(vertices, faces, 1.0, BodySettings(h=h, stiffness=1e4), accel=accel)
    lone = int(np.flatnonzero(np.diff(body.start) == 1)[0])
    i = body.start[lone]
    for step in range(1, 101):
        body.step()
        assert body.v[i, 2] == pytest.approx(10.0 * h * step)
        assert np.all(np.isfinite(body.x))
    assert body.x[i, 0] == 5.0


def test_tearing_every_edge_one_by_one_keeps_pieces_closed_and_finite():
    vertices, faces = cube_surface(2, 1.0)
    body = ElasticBody(vertices, faces, 1.0, BodySettings(h=1e-2, stiffness=1e4, beta=0.3, tearing=True, rule="edge"))
    rng = np.random.default_rng(1)
    body.v += rng.normal(0.0, 1.0, body.v.shape)
    pieces = []
    while True:
        glued = np.flatnonzero((body.mesh.twin >= 0) & ~body.mesh.cracked)
        if len(glued) == 0:
            break
        broken = np.zeros(len(body.mesh.twin), bool)
        broken[rng.choice(glued)] = True
        body.tear(broken | broken[np.maximum(body.mesh.twin, 0)])
        for _ in range(3):
            body.step()
            assert np.all(np.isfinite(body.x))
        _, all_faces, _ = body.closed_surface()
        assert _closed(all_faces)
        assert all(_closed(f) for _, f in body.pieces())
        pieces.append(body.n_clusters)
    assert np.all(np.diff(pieces) >= 0)  # pieces never merge
    assert body.n_clusters == len(faces) and np.all(np.diff(body.start) == 3)  # every triangle alone
    for _ in range(200):  # single triangles: planar clusters, still stable
        body.step()
    assert np.all(np.isfinite(body.x))


@pytest.mark.parametrize("quadratic", [False, True])
def test_rest_data_kept_for_untouched_clusters_equals_a_fresh_computation(quadratic):
    """After several tears, the reused per-cluster rest data matches recomputing every cluster."""
    vertices, faces = cube_surface(5, 1.0)
    body = ElasticBody(vertices, faces, 1.0, BodySettings(h=1e-2, quadratic=quadratic, tearing=True))
    rng = np.random.default_rng(3)
    for _ in range(6):
        biggest = int(np.argmax(np.diff(body.start)))
        vertex = int(rng.integers(body.start[biggest], body.start[biggest + 1]))
        corner = np.flatnonzero(body.mesh.origin == vertex)
        broken = np.zeros(len(body.mesh.twin), bool)
        broken[3 * (corner // 3) + (corner % 3 + 1) % 3] = True
        twin = body.mesh.twin
        body.tear((twin >= 0) & (broken | broken[np.maximum(twin, 0)]))
    # one triangle off the body: its three vertices split, the body keeps as many vertices as it had
    face = int(np.flatnonzero(body.cluster[body.mesh.faces[:, 0]] == np.argmax(np.diff(body.start)))[-1])
    twin = body.mesh.twin
    broken = np.zeros(len(twin), bool)
    broken[3 * face : 3 * face + 3] = True
    before = body.n_clusters
    body.tear((twin >= 0) & (broken | broken[np.maximum(twin, 0)]))
    assert body.n_clusters == before + 1
    kept = [body.q_rest.copy(), body.aqq_pinv.copy(), body.null_proj.copy(), body.qt.copy(), body.qpinv.copy()]
    body._rest_data(np.arange(body.n_clusters))
    fresh = [body.q_rest, body.aqq_pinv, body.null_proj, body.qt, body.qpinv]
    assert body.n_clusters >= 4
    for a, b in zip(kept, fresh):
        assert np.allclose(a, b, atol=1e-9)


def test_a_tear_conserves_mass_momentum_and_kinetic_energy():
    """Split vertices share their mass: the split itself adds no momentum or kinetic energy."""
    vertices, faces = cube_surface(4, 1.0)
    body = ElasticBody(vertices, faces, 2.0, BodySettings(h=1e-2, tearing=True, rule="edge"))
    body.v[:] = np.random.default_rng(5).normal(0.0, 1.0, body.v.shape)
    totals = lambda: (  # noqa: E731
        (1 / body.inv_mass).sum(),
        ((1 / body.inv_mass)[:, None] * body.v).sum(0),
        0.5 * ((1 / body.inv_mass) * (body.v**2).sum(1)).sum(),
    )
    mass, momentum, kinetic = totals()
    body.tear(np.ones(len(body.mesh.twin), bool))  # every triangle alone: every vertex split
    assert body.n_clusters == len(faces)
    after = totals()
    assert after[0] == pytest.approx(mass) and after[0] == pytest.approx(2.0)
    assert after[1] == pytest.approx(momentum) and after[2] == pytest.approx(kinetic)
