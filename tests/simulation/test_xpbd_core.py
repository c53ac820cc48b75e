"""Hard cases of the XPBD core (issue 6): each asserts a bound, no NaN, no explosion."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from xpbd_scenes import bowl_mesh, box_mesh, solver_run

from nodes.simulation.collider import signed_distance_grid
from nodes.simulation.settings import SolverSettings
from nodes.simulation.shape_matching import extract_rotation

GROUND = [box_mesh([-40, -40, -4], [40, 40, 0], "ground")]


def ground_sdf(lo=(-30, -30, -3), hi=(30, 30, 60), pitch=0.5):
    return signed_distance_grid(GROUND, np.array(lo, float), np.array(hi, float), pitch)


def cluster_bar(n=4, spacing=1.0):
    """Collinear particles along x: the degenerate case for polar decompositions."""
    return np.stack([np.arange(n) * spacing - (n - 1) * spacing / 2, np.zeros(n), np.zeros(n)], 1)


def make(elements, radius, masses, settings, sdf=None):
    """``SolverRun`` from a list of (local particle offsets, world centre, rotation) per element."""
    xs, qs, ws, sizes, quats = [], [], [], [], []
    for (local, centre, rot), mass in zip(elements, masses):
        q = local - local.mean(axis=0)
        xs.append(q @ rot.T + centre)
        qs.append(q)
        ws.append(np.full(len(q), len(q) / mass))
        sizes.append(len(q))
        quats.append(Rotation.from_matrix(rot).as_quat()[[3, 0, 1, 2]])
    x = np.concatenate(xs)
    return solver_run(
        x,
        np.full(len(x), radius),
        np.concatenate(ws),
        np.r_[0, np.cumsum(sizes)],
        np.concatenate(qs),
        np.array(quats),
        settings,
        sdf=sdf,
    )


def finite(run):
    return np.isfinite(run.state.x).all() and np.isfinite(run.state.v).all()


def pairwise(p):
    return np.linalg.norm(p[:, None] - p[None], axis=-1)


def test_zero_compliance_keeps_shape():
    settings = SolverSettings(
        frozenset({"gravity", "contact", "friction", "collider"}), compliance=0.0, substeps=10, iterations=4
    )
    bar = cluster_bar()
    elements = [
        (bar, np.array([0, 0, 2.0 + 3 * k]), Rotation.from_euler("z", 30 * k, degrees=True).as_matrix())
        for k in range(3)
    ]
    s = make(elements, 0.6, [0.025] * 3, settings, ground_sdf())
    for _ in range(60):
        s.frame()
    assert finite(s)
    for c in range(3):
        p = s.state.x[s.model.start[c] : s.model.start[c + 1]]
        assert np.abs(pairwise(p) - pairwise(bar)).max() < 0.05
    assert s.state.x[:, 2].min() > 0.6 * 0.9  # resting on the ground, not through it


def test_mass_ratio_1_to_1000_is_stable():
    settings = SolverSettings(frozenset({"gravity", "contact", "friction", "collider"}), compliance=1e-6)
    square = np.array([[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0], [0, 0, 1.0]])
    elements = [(square, np.array([0, 0, 1.0]), np.eye(3)), (square, np.array([0.3, 0, 3.2]), np.eye(3))]
    s = make(elements, 0.9, [0.025, 25.0], settings, ground_sdf())  # heavy element on the light one
    for _ in range(90):
        s.frame()
    assert finite(s)
    dg = s.solver.diagnostics
    assert dg.penetration[-1] < 0.5
    assert s.state.x[:, 2].max() < 6.0  # nothing launched
    assert dg.kinetic_energy[-1] < 1e-2 * max(dg.kinetic_energy)


@pytest.mark.parametrize("damping", [0.0, 0.1])
def test_deep_initial_overlap_separates_without_explosion(damping):
    """Pre-stabilisation separates the blob without velocity; only the allowance decay (documented
    speed ≤ decay rate·r per contact) adds some, and damping takes that out again."""
    effects = {"contact", "damping"} if damping else {"contact"}
    settings = SolverSettings(frozenset(effects), substeps=10, iterations=2, damping=damping)
    n = 64
    x = np.zeros((n, 3))  # every particle at the same point
    s = solver_run(
        x,
        np.full(n, 0.5),
        np.full(n, 40.0),
        np.arange(n + 1),
        np.zeros((n, 3)),
        np.tile([1.0, 0, 0, 0], (n, 1)),
        settings,
    )
    clamp = 0.5 / settings.h
    for _ in range(120):
        s.frame()
        assert np.linalg.norm(s.state.v, axis=1).max() < 0.4 * clamp  # no burst towards the speed clamp
    assert finite(s)
    assert s.solver.diagnostics.penetration[-1] < 0.25
    if damping:
        assert np.linalg.norm(s.state.x, axis=1).max() < 20.0  # a compact cluster


def test_large_time_step_stays_bounded():
    settings = SolverSettings(
        frozenset({"gravity", "contact", "friction", "collider"}), dt=0.5, substeps=1, iterations=2, compliance=1e-6
    )
    bar = cluster_bar(3)
    elements = [(bar, np.array([0.3 * k, 0, 1 + 2.0 * k]), np.eye(3)) for k in range(6)]
    s = make(elements, 0.6, [0.025] * 6, settings, ground_sdf())
    for _ in range(20):
        s.frame()
    assert finite(s)
    assert s.state.x[:, 2].min() > 0.0 and s.state.x[:, 2].max() < 30.0


def test_fast_grains_do_not_tunnel_through_thin_bowl_wall():
    bowl = bowl_mesh(radius=20.0, wall=0.8, rim=0.3, segments=64)
    sdf = signed_distance_grid([bowl], np.array([-24.0, -24, -24]), np.array([24.0, 24, 10]), 0.25)
    settings = SolverSettings(frozenset({"contact", "collider"}), substeps=4, iterations=1)
    rng = np.random.default_rng(1)
    n = 200
    x = rng.uniform(-4, 4, (n, 3))
    s = solver_run(
        x,
        np.full(n, 0.5),
        np.full(n, 40.0),
        np.arange(n + 1),
        np.zeros((n, 3)),
        np.tile([1.0, 0, 0, 0], (n, 1)),
        settings,
        sdf=sdf,
    )
    direction = x / np.linalg.norm(x, axis=1, keepdims=True)
    direction[:, 2] = -np.abs(direction[:, 2])
    s.state.v[:] = 20000.0 * direction  # 20 m/s towards the wall: 160× a radius per substep before the clamp
    inner = 20.0 - 0.8
    for _ in range(30):
        s.frame()
        assert np.linalg.norm(s.state.x, axis=1).max() < inner  # no particle ever reached the wall's far side
    assert finite(s)


def test_long_rest_decays_without_jitter_growth():
    settings = SolverSettings(
        frozenset({"gravity", "contact", "friction", "collider", "damping"}),
        damping=0.1,
        compliance=1e-6,
        sleep_speed=1.0,
    )
    bar = cluster_bar(3)
    rng = np.random.default_rng(0)
    elements = [
        (bar, np.r_[rng.uniform(-2, 2, 2), 1 + 1.3 * k], Rotation.random(random_state=k).as_matrix()) for k in range(12)
    ]
    s = make(elements, 0.6, [0.025] * 12, settings, ground_sdf())
    for _ in range(240):
        s.frame()
    ke = np.array(s.solver.diagnostics.kinetic_energy)
    assert finite(s)
    assert ke[-60:].max() <= 1e-3 * ke.max()
    assert ke[-30:].max() <= ke[-60:-30].max() + 1e-12  # no jitter growth at rest
    assert s.solver.diagnostics.sleeping[-1] > 0.5


@pytest.mark.parametrize("shape", ["collinear", "planar", "single"])
def test_degenerate_clusters_keep_proper_rotations(shape):
    local = {
        "collinear": cluster_bar(5),
        "planar": np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [2, 2, 0.0]]),
        "single": np.zeros((1, 3)),
    }[shape]
    settings = SolverSettings(frozenset({"gravity", "contact", "collider"}), compliance=1e-7, linear_deformation=0.5)
    elements = [
        (local, np.array([0.5 * k, 0, 1.5 + 2.5 * k]), Rotation.random(random_state=k).as_matrix()) for k in range(4)
    ]
    s = make(elements, 0.6, [0.025] * 4, settings, ground_sdf())
    for _ in range(60):
        s.frame()
    assert finite(s)
    rot = s.state.rotations()
    assert np.allclose(rot @ rot.transpose(0, 2, 1), np.eye(3), atol=1e-6)
    assert np.allclose(np.linalg.det(rot), 1.0, atol=1e-6)
    for c in range(4):
        p = s.state.x[s.model.start[c] : s.model.start[c + 1]]
        assert np.abs(pairwise(p) - pairwise(local)).max() < 0.25


def test_rotation_extraction_from_rank_one_matrix():
    q = np.array([1.0, 0, 0, 0])
    a = np.outer([0.0, 1.0, 0.0], [1.0, 0.0, 0.0])  # a collinear cluster turned from x to y
    rot = np.empty((3, 3))
    extract_rotation(a, q, 50, rot)
    assert np.allclose(rot @ [1.0, 0, 0], [0, 1.0, 0], atol=1e-6)
    assert np.isclose(np.linalg.det(rot), 1.0)


def test_bad_settings_are_rejected():
    with pytest.raises(ValueError, match="unknown effects"):
        SolverSettings(frozenset({"magnetism"}))
    with pytest.raises(ValueError, match="substeps"):
        SolverSettings(frozenset({"gravity"}), substeps=0)
    with pytest.raises(ValueError, match="watertight"):
        open_mesh = box_mesh([0, 0, 0], [1, 1, 1])
        from nodegraph.values import Mesh

        signed_distance_grid([Mesh(open_mesh.vertices, open_mesh.faces[:-2])], np.zeros(3), np.ones(3), 0.1)


def tall_pile(n, side, shock, frames, iterations=1):
    """n unit spheres dropped from a jittered grid into an open box of inner side ``side`` (mm)."""
    from xpbd_scenes import open_box

    per_row = int(side / 2.1)
    k = np.arange(n)
    x = np.stack([k % per_row, (k // per_row) % per_row, k // per_row**2], 1) * 2.1 + 1.05
    x = x + np.random.default_rng(0).uniform(-0.04, 0.04, x.shape)
    top = x[:, 2].max() + 2
    sdf = signed_distance_grid(
        open_box(side, wall=2.0, height=top), np.array([-2.0, -2, -2]), np.array([side + 2, side + 2, top]), 0.5
    )
    settings = SolverSettings(
        frozenset({"gravity", "contact", "friction", "collider"}),
        substeps=10,
        iterations=iterations,
        mu_s=0.5,
        mu_k=0.35,
        shock_propagation=shock,
    )
    s = solver_run(
        x,
        np.full(n, 1.0),
        np.full(n, 1.0),
        np.arange(n + 1),
        np.zeros((n, 3)),
        np.tile([1.0, 0, 0, 0], (n, 1)),
        settings,
        sdf=sdf,
    )
    for _ in range(frames):
        s.frame()
    return s


def test_tall_column_rests_on_its_base():
    """30 spheres stacked on the floor, 1 iteration: shock propagation carries the weight down."""
    n = 30
    x = np.stack([np.zeros(n), np.zeros(n), 1.05 + 2.1 * np.arange(n)], 1)
    sdf = signed_distance_grid(GROUND, np.array([-5.0, -5, -3]), np.array([5.0, 5, 70]), 0.5)
    settings = SolverSettings(
        frozenset({"gravity", "contact", "collider"}), substeps=10, iterations=1, shock_propagation=4.0
    )
    s = solver_run(
        x,
        np.ones(n),
        np.ones(n),
        np.arange(n + 1),
        np.zeros((n, 3)),
        np.tile([1.0, 0, 0, 0], (n, 1)),
        settings,
        sdf=sdf,
    )
    for _ in range(120):
        s.frame()
    assert finite(s)
    assert np.abs(s.state.x[:, :2]).max() < 1e-6  # still a column
    assert max(s.solver.diagnostics.penetration[-30:]) < 0.1
    assert s.state.x[:, 2].max() > 0.97 * (2 * n - 1)  # the top sphere is where a rigid stack puts it


def test_tall_pile_keeps_spheres_apart():
    """≈ 14 layers of unit spheres in a box (the xpbd defaults: 10 substeps × 2 iterations): max
    penetration stays below 0.2 r and the pile packs like random spheres (φ ≈ 0.55–0.64). Without
    shock propagation (or with the old averaged Jacobi) the same pile sinks to penetration ≈ 2 r."""
    s = tall_pile(2000, 24.0, shock=4.0, frames=60, iterations=2)
    assert finite(s)
    assert max(s.solver.diagnostics.penetration[-10:]) < 0.2
    z = s.state.x[:, 2]
    cut = 0.8 * np.percentile(z, 95)
    packing = (z < cut).sum() * (4 / 3) * np.pi / (24.0**2 * cut)
    assert 0.5 < packing < 0.68
