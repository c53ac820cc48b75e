"""Bend constraints along a long grain's axis — issue 6 (G: bend stiffness 10 for rice; Table 3 0–10).

Shape matching alone lets a long cluster sag like a soft block: each particle is pulled to one
fit of the whole element. For elongated clusters the particles are ordered along the principal
axis; each interior particle b gets a vector XPBD constraint against the chord between the two end
particles a, c: C = x_b − ((1 − t)·x_a + t·x_c) − R·d₀, t = b's rest position along the chord,
d₀ its rest offset from it, R the cluster rotation. It resists bending of the whole grain (not
rotation, hardly stretch); Gauss–Seidel along the chain, clusters in parallel. Nearest-neighbour
triples were tried first: a sag's curvature changes a 1-particle-spacing midpoint offset by only
≈ κℓ²/8, so at the shape-matching compliance they changed the sag of an 11-particle beam by < 0.2 %.
"""

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .shape_matching import quat_to_matrix


class BendRows(NamedTuple):
    """The bend constraints as ``bend_project`` takes them (``model.BendTriples.args()``)."""

    triples: np.ndarray  # (t, 3) end a, interior b, end c
    frac: np.ndarray  # (t,) chord fractions
    rest: np.ndarray  # (t, 3) rest offsets
    tstart: np.ndarray  # (m + 1,) per-cluster CSR


def bend_triples(q_rest: np.ndarray, start: np.ndarray, elongation: float = 1.5):
    """(triples (t, 3) particle indices (end a, interior b, end c), chord fractions (t,), rest offsets
    (t, 3), per-cluster CSR (m + 1)) for clusters of ≥ 3 particles whose rms extent along the
    principal axis is ≥ ``elongation`` × the next one."""
    m = len(start) - 1
    triples, frac, rest, counts = [], [], [], np.zeros(m, np.int64)
    for c in range(m):
        s, e = start[c], start[c + 1]
        if e - s < 3:
            continue
        q = q_rest[s:e]
        vals, vecs = np.linalg.eigh(q.T @ q)
        if not vals[2] >= elongation**2 * vals[1]:
            continue
        along = q @ vecs[:, 2]
        chain = np.argsort(along, kind="stable")
        a, cc = chain[0], chain[-1]
        for b in chain[1:-1]:
            t = (along[b] - along[a]) / (along[cc] - along[a])
            triples.append((s + a, s + b, s + cc))
            frac.append(t)
            rest.append(q[b] - ((1.0 - t) * q[a] + t * q[cc]))
        counts[c] = e - s - 2
    return (
        np.array(triples, np.int64).reshape(-1, 3),
        np.array(frac, float),
        np.array(rest, float).reshape(-1, 3),
        np.r_[0, np.cumsum(counts)].astype(np.int64),
    )


@njit(cache=True, parallel=True)
def bend_project(state, model, bends, lam, alpha_tilde):
    """One XPBD sweep of the bend constraints C = x_b − ((1 − t)·x_a + t·x_c) − R·d₀ (module docstring; λ
    accumulated in ``lam`` (t, 3), Δλ = (−C − α̃λ)/(Σ w + α̃)) of the clusters whose particles are ``awake``
    (``integrate.wake_flags``); returns max |C|. ``state``: ``StateArrays`` (x, quats, awake), ``model``:
    ``ModelArrays`` (w), ``bends``: ``BendRows``."""
    x, quats, awake = state.x, state.quats, state.awake
    w = model.w
    triples, frac, rest, tstart = bends.triples, bends.frac, bends.rest, bends.tstart
    m = tstart.shape[0] - 1
    worst = np.zeros(m)
    rots = np.empty((m, 3, 3))  # one allocation per sweep, not one per cluster inside the parallel loop
    for c in prange(m):
        if tstart[c + 1] == tstart[c] or not awake[triples[tstart[c], 1]]:
            continue
        rot = rots[c]
        quat_to_matrix(quats[c], rot)
        for t in range(tstart[c], tstart[c + 1]):
            a, b, e = triples[t, 0], triples[t, 1], triples[t, 2]
            t_ = frac[t]
            wsum = w[b] + (1.0 - t_) ** 2 * w[a] + t_ * t_ * w[e]
            if wsum <= 0.0:
                continue
            for k in range(3):
                d0 = rot[k, 0] * rest[t, 0] + rot[k, 1] * rest[t, 1] + rot[k, 2] * rest[t, 2]
                cval = x[b, k] - (1.0 - t_) * x[a, k] - t_ * x[e, k] - d0
                worst[c] = max(worst[c], abs(cval))
                dl = (-cval - alpha_tilde * lam[t, k]) / (wsum + alpha_tilde)
                lam[t, k] += dl
                x[b, k] += w[b] * dl
                x[a, k] -= (1.0 - t_) * w[a] * dl
                x[e, k] -= t_ * w[e] * dl
    return worst.max() if m > 0 else 0.0
