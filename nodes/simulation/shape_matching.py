"""Shape-matching cluster constraint per element — SPEC §5 (Müller et al. 2005), as an XPBD
constraint (Macklin et al. 2016) with linear (U eq. 3.19) or quadratic deformation (Müller et al. 2005
§4.3: q̃ = [q, q², cross terms], goal (β·Ã + (1−β)·[R 0 0])·q̃ + x_cm).

The rotation of A_pq is extracted with Müller et al. 2016 ("A robust method to extract the
rotational part of deformations"): a quaternion warm-started from the previous step, which always
returns a proper rotation and leaves the unobservable axis alone when the cluster is collinear or
planar — where Jacobi-on-AᵀA / SVD polar decompositions flip or blow up. 3×3 algebra is written
out on scratch arrays: temporaries allocated per cluster per iteration cost more than the maths.
"""

from typing import NamedTuple

import numpy as np
from numba import njit, prange

BLOCK = 64  # clusters per parallel task (one scratch allocation per block)


class LinearMoments(NamedTuple):
    """The linear goal's rest data per cluster (``rest_moments``)."""

    aqq_pinv: np.ndarray  # (m, 3, 3) A_qq⁺
    null_proj: np.ndarray  # (m, 3, 3) projector on A_qq's null space


class QuadraticMoments(NamedTuple):
    """The quadratic goal's rest data (``quadratic_moments``); clusters whose flag is unset keep the linear goal."""

    qt: np.ndarray  # (n, 9) q̃ per particle
    qpinv: np.ndarray  # (m, 9, 9) Ã_qq⁻¹ per cluster
    flags: np.ndarray  # (m,) bool


class MatchRule(NamedTuple):
    """What ``shape_match_project`` takes of the settings (once per run, ``solver.XpbdSolver``)."""

    alpha_tilde: float  # XPBD α̃ = compliance / h²
    beta: float  # linear deformation share β of the goal (SPEC §5)
    rot_iters: int  # iterations of the rotation extraction


class GoalScratch(NamedTuple):
    """3×3 and 3×9 work matrices of one cluster's goal map: A_pq, R, the linear goal, Ã_pq, the quadratic goal."""

    apq: np.ndarray
    rot: np.ndarray
    goal: np.ndarray
    apq9: np.ndarray
    goal9: np.ndarray


@njit(cache=True, inline="always")
def quat_to_matrix(q, out):
    w, x, y, z = q[0], q[1], q[2], q[3]
    out[0, 0] = 1 - 2 * (y * y + z * z)
    out[0, 1] = 2 * (x * y - w * z)
    out[0, 2] = 2 * (x * z + w * y)
    out[1, 0] = 2 * (x * y + w * z)
    out[1, 1] = 1 - 2 * (x * x + z * z)
    out[1, 2] = 2 * (y * z - w * x)
    out[2, 0] = 2 * (x * z - w * y)
    out[2, 1] = 2 * (y * z + w * x)
    out[2, 2] = 1 - 2 * (x * x + y * y)


@njit(cache=True)
def extract_rotation(a, q, max_iter, rot):
    """Rotate quaternion ``q`` (in place, w-x-y-z) towards the rotation of ``a`` (Müller 2016 eq. 7);
    ``rot`` is 3×3 scratch and ends holding the rotation matrix."""
    for _ in range(max_iter):
        quat_to_matrix(q, rot)
        ox = 0.0
        oy = 0.0
        oz = 0.0
        dot = 0.0
        for c in range(3):
            rx, ry, rz = rot[0, c], rot[1, c], rot[2, c]
            ax, ay, az = a[0, c], a[1, c], a[2, c]
            ox += ry * az - rz * ay
            oy += rz * ax - rx * az
            oz += rx * ay - ry * ax
            dot += rx * ax + ry * ay + rz * az
        inv = 1.0 / (abs(dot) + 1e-9)
        ox *= inv
        oy *= inv
        oz *= inv
        angle = np.sqrt(ox * ox + oy * oy + oz * oz)
        if angle < 1e-9:
            break
        s = np.sin(0.5 * angle) / angle
        dw, dx, dy, dz = np.cos(0.5 * angle), ox * s, oy * s, oz * s
        w0, x0, y0, z0 = q[0], q[1], q[2], q[3]
        q[0] = dw * w0 - dx * x0 - dy * y0 - dz * z0
        q[1] = dw * x0 + dx * w0 + dy * z0 - dz * y0
        q[2] = dw * y0 - dx * z0 + dy * w0 + dz * x0
        q[3] = dw * z0 + dx * y0 - dy * x0 + dz * w0
        norm = np.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
        for k in range(4):
            q[k] /= norm
    quat_to_matrix(q, rot)


@njit(cache=True, inline="always")
def _mass(w):
    return 1.0 / w if w > 0.0 else 1e12


@njit(cache=True)
def _goal_scratch():
    return GoalScratch(np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 9)), np.empty((3, 9)))


def particle_masses(w: np.ndarray) -> np.ndarray:
    """Masses from inverse masses, 1e12 for static particles (w = 0): ``_mass`` outside the kernels."""
    return np.where(w > 0, 1.0 / np.maximum(w, 1e-300), 1e12)


@njit(cache=True, inline="always")
def _step_to_goal(x, w, lam, alpha_tilde, i, k, g):
    """XPBD step of coordinate k of particle i towards its goal g, with λ accumulation (SPEC §5,
    Macklin et al. 2016); returns |C| before the step."""
    cval = x[i, k] - g
    dl = (-cval - alpha_tilde * lam[i, k]) / (w[i] + alpha_tilde)
    lam[i, k] += dl
    x[i, k] += w[i] * dl
    return abs(cval)


@njit(cache=True, inline="always")
def _copy3(src, dst):
    """dst[:3, :3] = src element by element: an array assignment compiles numba's shape-mismatch error message
    (string formatting, ≈ 1 CPU s of a first run's compiling)."""
    for r_ in range(3):
        for c_ in range(3):
            dst[r_, c_] = src[r_, c_]


@njit(cache=True, inline="always")
def _det3(a):
    return (
        a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
        - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
        + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0])
    )


@njit(cache=True, inline="always")
def centre_of_mass(x, w, s, e):
    """x_cm of the cluster's particles s..e (SPEC §5); of velocities, the cluster's velocity."""
    total = 0.0
    cx = 0.0
    cy = 0.0
    cz = 0.0
    for i in range(s, e):
        m = _mass(w[i])
        total += m
        cx += m * x[i, 0]
        cy += m * x[i, 1]
        cz += m * x[i, 2]
    return cx / total, cy / total, cz / total


@njit(cache=True, inline="always")
def _moment_matrix(x, w, q, s, e, cx, cy, cz, out):
    """A_pq = Σ m_i p_i q_iᵀ with p_i = x_i − x_cm (SPEC §5); q holds 3 (linear) or 9 (quadratic) rest columns."""
    out[:, :] = 0.0
    for i in range(s, e):
        m = _mass(w[i])
        px = m * (x[i, 0] - cx)
        py = m * (x[i, 1] - cy)
        pz = m * (x[i, 2] - cz)
        for c in range(q.shape[1]):
            out[0, c] += px * q[i, c]
            out[1, c] += py * q[i, c]
            out[2, c] += pz * q[i, c]


@njit(cache=True)
def linear_goal_matrix(x, w, q_rest, start, c, quats, moments, beta, rot_iters, scratch):
    """Goal map of cluster c into ``scratch.goal`` (3×3): R, or β·A/∛det A + (1−β)·R (SPEC §5, U eq. 3.19);
    returns x_cm. Shared by the xpbd constraint and the tearing body's integration."""
    s, e = start[c], start[c + 1]
    apq, rot, goal = scratch.apq, scratch.rot, scratch.goal
    pinv, null = moments.aqq_pinv[c], moments.null_proj[c]
    cx, cy, cz = centre_of_mass(x, w, s, e)
    _moment_matrix(x, w, q_rest, s, e, cx, cy, cz, apq)
    extract_rotation(apq, quats[c], rot_iters, rot)
    _copy3(rot, goal)
    if beta > 0.0:
        # A = A_pq·A_qq⁺ + R·P_null (unobservable axes follow R), volume-normalised (SPEC §5)
        for r_ in range(3):
            for c_ in range(3):
                v = 0.0
                for k in range(3):
                    v += apq[r_, k] * pinv[k, c_] + rot[r_, k] * null[k, c_]
                goal[r_, c_] = v
        det = _det3(goal)
        if det > 1e-6:
            f = beta / np.cbrt(det)
            for r_ in range(3):
                for c_ in range(3):
                    goal[r_, c_] = f * goal[r_, c_] + (1.0 - beta) * rot[r_, c_]
        else:
            _copy3(rot, goal)
    return cx, cy, cz


@njit(cache=True)
def _match_cluster(x, w, q_rest, start, c, quats, moments, lam, alpha_tilde, beta, rot_iters, scratch):
    """Project cluster c; returns its max |C|."""
    cx, cy, cz = linear_goal_matrix(x, w, q_rest, start, c, quats, moments, beta, rot_iters, scratch)
    goal = scratch.goal
    res = 0.0
    cm = (cx, cy, cz)
    for i in range(start[c], start[c + 1]):
        for k in range(3):
            g = cm[k] + goal[k, 0] * q_rest[i, 0] + goal[k, 1] * q_rest[i, 1] + goal[k, 2] * q_rest[i, 2]
            res = max(res, _step_to_goal(x, w, lam, alpha_tilde, i, k, g))
    return res


@njit(cache=True)
def quadratic_goal_matrix(x, w, q_rest, start, c, quats, quadratic, beta, rot_iters, scratch):
    """Quadratic goal map of cluster c into ``scratch.goal9`` (3×9): (β·Ã + (1−β)·[R 0 0]) (SPEC §5);
    returns x_cm. The linear 3×3 block of Ã is volume-normalised as in the linear mode; the quadratic
    block is scaled by β only. ``quadratic.qt`` holds centred quadratic columns, so the goal keeps x_cm."""
    s, e = start[c], start[c + 1]
    apq, rot, apq9, goal9 = scratch.apq, scratch.rot, scratch.apq9, scratch.goal9
    qpinv = quadratic.qpinv[c]
    cx, cy, cz = centre_of_mass(x, w, s, e)
    _moment_matrix(x, w, q_rest, s, e, cx, cy, cz, apq)
    _moment_matrix(x, w, quadratic.qt, s, e, cx, cy, cz, apq9)
    extract_rotation(apq, quats[c], rot_iters, rot)
    goal9[:, :] = 0.0
    for r_ in range(3):
        for c_ in range(3):
            goal9[r_, c_] = rot[r_, c_]
    if beta > 0.0:
        for r_ in range(3):
            for c_ in range(9):
                v = 0.0
                for k in range(9):
                    v += apq9[r_, k] * qpinv[k, c_]
                goal9[r_, c_] = v
        det = _det3(goal9[:, :3])
        if det > 1e-6:
            f = beta / np.cbrt(det)
            for r_ in range(3):
                for c_ in range(3):
                    goal9[r_, c_] = f * goal9[r_, c_] + (1.0 - beta) * rot[r_, c_]
                for c_ in range(3, 9):
                    goal9[r_, c_] *= beta
        else:
            goal9[:, :] = 0.0
            for r_ in range(3):
                for c_ in range(3):
                    goal9[r_, c_] = rot[r_, c_]
    return cx, cy, cz


@njit(cache=True)
def _match_cluster_quadratic(x, w, q_rest, start, c, quats, quadratic, lam, alpha_tilde, beta, rot_iters, scratch):
    """Project cluster c with the quadratic goal (SPEC §5); returns its max |C|."""
    cx, cy, cz = quadratic_goal_matrix(x, w, q_rest, start, c, quats, quadratic, beta, rot_iters, scratch)
    goal9, qt = scratch.goal9, quadratic.qt
    res = 0.0
    cm = (cx, cy, cz)
    for i in range(start[c], start[c + 1]):
        for k in range(3):
            g = cm[k]
            for j in range(9):
                g += goal9[k, j] * qt[i, j]
            res = max(res, _step_to_goal(x, w, lam, alpha_tilde, i, k, g))
    return res


@njit(cache=True, parallel=True)
def shape_match_project(state, model, moments, lam, rule, quadratic=None):
    """One XPBD sweep of C_i = x_i − g_i per particle, g_i = (β·A + (1−β)·R)·q_i + x_cm (SPEC §5);
    with ``quadratic`` (``QuadraticMoments``), the quadratic goal for the clusters whose flag is set (the
    others, too few or degenerate particles, keep the linear goal, from ``moments``: ``LinearMoments``).
    Clusters whose particles are asleep (``awake`` per particle, ``integrate.wake_flags``) are skipped:
    they keep their shape.

    Clusters are disjoint, so the loop over clusters is race-free and updates ``x`` in place.
    ``lam`` (n, 3) accumulates λ over the iterations of a substep; returns the max |C| seen.
    ``state``: ``StateArrays`` (x, quats, awake), ``model``: ``ModelArrays`` (w, q_rest, start), ``rule``:
    ``MatchRule`` (α̃, β, rotation iterations).
    """
    x, quats, awake = state.x, state.quats, state.awake
    w, q_rest, start = model.w, model.q_rest, model.start
    alpha_tilde, beta, rot_iters = rule.alpha_tilde, rule.beta, rule.rot_iters
    m = start.shape[0] - 1
    worst = np.zeros(m)
    blocks = (m + BLOCK - 1) // BLOCK
    for b in prange(blocks):
        scratch = _goal_scratch()
        for c in range(b * BLOCK, min(m, (b + 1) * BLOCK)):
            if start[c + 1] - start[c] < 2 or not awake[start[c]]:
                continue
            if quadratic is not None and quadratic.flags[c]:
                worst[c] = _match_cluster_quadratic(
                    x, w, q_rest, start, c, quats, quadratic, lam, alpha_tilde, beta, rot_iters, scratch
                )
            else:
                worst[c] = _match_cluster(
                    x, w, q_rest, start, c, quats, moments, lam, alpha_tilde, beta, rot_iters, scratch
                )
    return worst.max() if m > 0 else 0.0


@njit(cache=True)
def shape_match_goals(x, w, q_rest, start, quats, moments, beta, rot_iters, quadratic, goals):
    """Goal positions g_i of every particle (SPEC §5: g_i = (β·A + (1−β)·R)·q_i + x_cm, quadratic where
    ``quadratic.flags[c]``) into ``goals``, for integrators that move towards them themselves (U eq. 3.16) —
    the same goal maps as ``shape_match_project``. A cluster of one particle has no shape: g = x."""
    scratch = _goal_scratch()
    goal, goal9, qt = scratch.goal, scratch.goal9, quadratic.qt
    for c in range(start.shape[0] - 1):
        s, e = start[c], start[c + 1]
        if e - s < 2:
            for i in range(s, e):
                goals[i, :] = x[i, :]
        elif quadratic.flags[c]:
            cx, cy, cz = quadratic_goal_matrix(x, w, q_rest, start, c, quats, quadratic, beta, rot_iters, scratch)
            for i in range(s, e):
                for k in range(3):
                    g = (cx, cy, cz)[k]
                    for j in range(9):
                        g += goal9[k, j] * qt[i, j]
                    goals[i, k] = g
        else:
            cx, cy, cz = linear_goal_matrix(x, w, q_rest, start, c, quats, moments, beta, rot_iters, scratch)
            for i in range(s, e):
                for k in range(3):
                    goals[i, k] = (
                        (cx, cy, cz)[k]
                        + goal[k, 0] * q_rest[i, 0]
                        + goal[k, 1] * q_rest[i, 1]
                        + goal[k, 2] * q_rest[i, 2]
                    )


def quadratic_moments(q_rest: np.ndarray, w: np.ndarray, start: np.ndarray, conditioning: float = 1e-4):
    """Per particle q̃ (n, 9) and per cluster Ã_qq⁻¹ (m, 9, 9) and a flag: quadratic or linear (SPEC §5).

    q̃ = [qx, qy, qz, qx², qy², qz², qx·qy, qy·qz, qz·qx]; the six quadratic columns are divided by
    the cluster's rms radius (same units as q, better conditioned) and centred on the cluster's
    mass-weighted mean, so Σ m q̃ = 0 and the goal keeps x_cm (uncentred, a bent goal drags the
    cluster's centre and the element creeps). A cluster with < 10 particles, or whose 9×9 Ã_qq has
    eigenvalue ratio below ``conditioning`` (collinear, planar, or too few distinct positions for
    the nine modes), gets the linear goal: a pseudo-inverse would leave its unobservable quadratic
    modes to fit noise.
    """
    from ..values import Aggregate

    m = len(start) - 1
    qt = np.zeros((len(q_rest), 9))
    qpinv = np.zeros((m, 9, 9))
    quadratic = np.zeros(m, np.bool_)
    mass = particle_masses(w)
    for c in range(m):
        s, e = start[c], start[c + 1]
        q = q_rest[s:e]
        mc = mass[s:e]
        scale = np.sqrt((mc * (q * q).sum(axis=1)).sum() / mc.sum())
        if not scale > 0:
            qt[s:e, :3] = q
            continue
        quad = Aggregate.monomials(q) / scale
        quad -= (mc[:, None] * quad).sum(axis=0) / mc.sum()
        qt[s:e] = np.concatenate([q, quad], axis=1)
        if e - s < 10:
            continue
        aqq = (qt[s:e] * mc[:, None]).T @ qt[s:e]
        vals, vecs = np.linalg.eigh(aqq)
        if vals[0] > conditioning * vals[-1]:
            qpinv[c] = (vecs / vals) @ vecs.T
            quadratic[c] = True
    return qt, qpinv, quadratic


# an axis along which a cluster's second moment is below this share of its largest is not observed: a grain whose
# particles lie within 0.07–0.11 mm of its mid-plane (moment ratio 0.002–0.006, 8 of the main job's 16 variants) had
# its thickness stretch fitted from that spread, and 21 of its 1,551 grains were drawn squashed to 0.50–0.73 of their
# thickness; a broken grain's 3-D cluster is at 0.14
UNOBSERVED = 0.01


def rest_moments(q_rest: np.ndarray, w: np.ndarray, start: np.ndarray, tolerance: float = UNOBSERVED):
    """Per cluster A_qq⁺ (pseudo-inverse of Σ m q qᵀ) and the projector on its null space.

    Collinear/planar clusters have a (near-)singular A_qq; the pseudo-inverse fits what the particles can
    observe and the null-space projector lets those axes follow the rotation only (SPEC §5).
    """
    m = len(start) - 1
    pinv = np.zeros((m, 3, 3))
    null = np.zeros((m, 3, 3))
    mass = particle_masses(w)
    for c in range(m):
        q = q_rest[start[c] : start[c + 1]]
        aqq = (q * mass[start[c] : start[c + 1], None]).T @ q
        vals, vecs = np.linalg.eigh(aqq)
        keep = vals > tolerance * max(vals.max(), 1e-300)
        pinv[c] = (vecs[:, keep] / vals[keep]) @ vecs[:, keep].T
        null[c] = vecs[:, ~keep] @ vecs[:, ~keep].T
    return pinv, null
