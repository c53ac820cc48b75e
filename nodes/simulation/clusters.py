"""Elements → particle clusters: a sphere packing of each element's volume — SPEC §3 (G: simulate
a low-resolution proxy, carry the high-resolution grain along).

Per distinct element mesh: a signed distance grid φ of the body (yolk faces, ``parts == 1``, excluded);
every sphere is centred on an interior grid point with radius = its depth (−φ; measured on the mesh
beyond φ's exact band), so it touches the surface from inside and never sticks out (SPEC §2.5's medial
spheres, S §3.2.2). The spheres are chosen to cover the shell (issue 17: where the union leaves the
surface uncovered, meshes whose spheres merely touch cut into each other): the deepest point, then a
greedy set cover at the least tolerance τ (bisected) that the count allows, refined by single-sphere
swaps (``_cover``). The gap of a shell vertex v to the union, gap(v) = min_k(|v − c_k| − r_k), is what
the cover minimises (worst first, then summed). Once every vertex is within a quarter cell (a round
egg: its deepest sphere), the rest of the count spreads through the core (farthest-point). When the
count could carry the quadratic goal (≥ 10) but the cover's centres cannot observe its nine modes (a
round grain's maximal spheres all lie on its axis), cover spheres are traded for core points until it
can, and the rest covers anew around them (``quadratic=False`` skips this for a linear run).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit


@njit(cache=True)
def _gap_matrix(points, depths, shell):
    """(candidates, shell vertices) gap |v − c| − r of each vertex to each candidate sphere (> 0: outside)."""
    out = np.empty((points.shape[0], shell.shape[0]))
    for c in range(points.shape[0]):
        for v in range(shell.shape[0]):
            dx = shell[v, 0] - points[c, 0]
            dy = shell[v, 1] - points[c, 1]
            dz = shell[v, 2] - points[c, 2]
            out[c, v] = np.sqrt(dx * dx + dy * dy + dz * dz) - depths[c]
    return out


@njit(cache=True)
def _greedy_cover(gaps, gaps_t, base, tau, budget):
    """Greedy set cover at tolerance ``tau``: pick (lowest index on ties) the candidate covering most
    vertices still farther than ``tau`` outside (``base``: their gap to the spheres kept already);
    the picks, and whether they cover every vertex within ``budget`` picks."""
    n_cand, n_vert = gaps.shape
    uncovered = base > tau
    left = int(uncovered.sum())
    counts = np.zeros(n_cand, np.int64)
    for c in range(n_cand):
        n = 0
        for v in range(n_vert):
            if uncovered[v] and gaps[c, v] <= tau:
                n += 1
        counts[c] = n
    picks = np.empty(budget, np.int64)
    k = 0
    while left > 0 and k < budget:
        best = int(np.argmax(counts))
        if counts[best] == 0:
            break
        picks[k] = best
        k += 1
        for v in range(n_vert):
            if uncovered[v] and gaps[best, v] <= tau:
                uncovered[v] = False
                left -= 1
                for c in range(n_cand):
                    if gaps_t[v, c] <= tau:
                        counts[c] -= 1
    return picks[:k], left == 0


@njit(cache=True)
def _best_candidate(gaps, others, order, allowed, worst_bound, sum_bound, by_sum):
    """The ``allowed`` candidate (lowest index on ties) that, joined to spheres whose gap per vertex
    is ``others``, gives a worst gap below ``worst_bound`` (``by_sum`` false: the least such), or a
    summed outside gap below ``sum_bound`` with the worst no more than ``worst_bound`` (``by_sum``
    true: the least such sum); −1 if none. ``order``: vertices, worst first (prunes early)."""
    best, best_worst, best_sum = -1, worst_bound, sum_bound
    for c in range(gaps.shape[0]):
        if not allowed[c]:
            continue
        worst, total, better = 0.0, 0.0, True
        for v in order:
            g = min(gaps[c, v], others[v])
            worst = max(worst, g)
            total += max(g, 0.0)
            if (worst >= best_worst) if not by_sum else (worst > worst_bound or total >= best_sum):
                better = False
                break
        if better:
            best, best_worst, best_sum = c, (worst if not by_sum else best_worst), total
    return best


def _quadratic_observable(centres: np.ndarray) -> bool:
    """Whether the quadratic goal (SPEC §5, ``shape_matching.quadratic_moments``, equal masses) sees all
    nine modes of a cluster at ``centres``, with a tenfold margin on its conditioning threshold."""
    from .shape_matching import quadratic_moments

    q = centres - centres.mean(axis=0)
    return bool(quadratic_moments(q, np.ones(len(q)), np.array([0, len(q)]), conditioning=1e-3)[2][0])


def _whitening(points: np.ndarray) -> np.ndarray:
    """3×3 map that gives ``points`` unit spread along each principal axis (a thin core's cross-section
    counts as much as its length when spreading particles through it)."""
    vals, vecs = np.linalg.eigh(np.cov(points.T) if len(points) > 1 else np.eye(3))
    return vecs / np.sqrt(np.maximum(vals, 1e-12 * max(vals.max(), 1e-300)))


def _core_fill(points: np.ndarray, depths: np.ndarray, chosen: np.ndarray, total: int) -> np.ndarray:
    """``chosen`` and, up to ``total``, farthest-point picks among the points at least half as deep as the
    deepest (the former clusters' core half): where the cover needs fewer spheres (a round egg), the rest
    spreads the cluster."""
    core = np.flatnonzero(depths >= 0.5 * depths.max())
    picks = list(chosen)
    away = np.linalg.norm(points[core, None, :] - points[picks][None, :, :], axis=2).min(axis=1)
    while len(picks) < total and away.max() > 0:
        best = int(np.argmax(away))
        picks.append(int(core[best]))
        away = np.minimum(away, np.linalg.norm(points[core] - points[core[best]], axis=1))
    return np.asarray(picks, np.int64)


def _spread_through_core(gaps, points, depths, chosen: np.ndarray) -> tuple[np.ndarray, int]:
    """(picks, traded): ``chosen`` (the deepest first) with cover spheres traded one at a time for core
    points (placed after the deepest) until the quadratic goal observes the cluster
    (``_quadratic_observable``); (``chosen``, 0) if trading half the count does not do it. Each trade
    drops the sphere whose loss raises the worst gap least and adds the core point (at least half as
    deep as the deepest) farthest from the rest, distances whitened (``_whitening``)."""
    core = np.flatnonzero(depths >= 0.5 * depths.max())
    whiten = _whitening(points[core])
    picks, traded = list(chosen), 0
    while not _quadratic_observable(points[picks]):
        if traded == len(chosen) // 2:
            return chosen, 0
        movable = range(1 + traded, len(picks))  # neither the deepest nor a core point already traded in
        losses = [np.delete(gaps[picks], j, axis=0).min(axis=0).max() for j in movable]
        picks.pop(movable[int(np.argmin(losses))])
        away = np.linalg.norm((points[core, None, :] - points[picks][None, :, :]) @ whiten, axis=2).min(axis=1)
        picks.insert(1 + traded, int(core[np.argmax(away)]))
        traded += 1
    return np.asarray(picks, np.int64), traded


def _cover(gaps, points, fixed, total: int, tolerance: float, reach: float, enough: float, sample: int = 300):
    """Indices of up to ``total`` candidate spheres (``fixed`` first; fewer once the worst gap is down to
    ``enough`` or no sphere lowers it) whose union covers the shell vertices: the least tolerance τ
    (bisected to ``tolerance``) at which a greedy set cover (``_greedy_cover``, on every k-th vertex,
    about ``sample`` of them) needs at most the spheres left, then single-sphere swaps (all vertices)
    that lower the worst gap, then the summed outside gap with the worst kept (a sphere moves within
    ``reach``). ``gaps``: (candidates, vertices) from ``_gap_matrix``; ``points``: the centres."""
    budget = total - len(fixed)
    if budget == 0:
        return fixed
    coarse = np.ascontiguousarray(gaps[:, :: max(1, gaps.shape[1] // sample)])
    coarse_t = np.ascontiguousarray(coarse.T)
    base = coarse[fixed].min(axis=0) if len(fixed) else np.full(coarse.shape[1], np.inf)
    lo = max(float(coarse.min(axis=0).max()), enough)  # no union beats each vertex's nearest sphere
    single = int(np.argmin(coarse.max(axis=1)))  # the one sphere with the least worst gap
    hi = min(float(base.max()), float(coarse[single].max()))
    picks, covered = _greedy_cover(coarse, coarse_t, base, hi, budget)
    if not covered:
        picks = np.array([single], np.int64)
    while hi - lo > tolerance:
        tau = 0.5 * (lo + hi)
        found, covered = _greedy_cover(coarse, coarse_t, base, tau, budget)
        if covered:
            hi, picks = tau, found
        else:
            lo = tau
    chosen = np.concatenate([fixed, picks])
    taken = np.zeros(len(gaps), np.bool_)
    taken[chosen] = True
    gap = gaps[chosen].min(axis=0)
    while len(chosen) < total and gap.max() > enough:  # the cover needed fewer: lower the worst gap most
        best = _best_candidate(gaps, gap, np.argsort(-gap, kind="stable"), ~taken, gap.max(), np.inf, False)
        if best < 0:  # covered as well as the candidates allow (a round egg by its deepest sphere)
            break
        chosen = np.append(chosen, best)
        taken[best] = True
        gap = np.minimum(gap, gaps[best])
    for by_sum in (False, True):
        for _ in range(2 if by_sum else 3):
            moved = False
            order = np.argsort(-gaps[chosen].min(axis=0), kind="stable")  # worst vertices first: prunes early
            for j in range(len(fixed), len(chosen)):
                others = np.delete(chosen, j)
                gap = gaps[others].min(axis=0)
                now = np.minimum(gap, gaps[chosen[j]])
                allowed = ~taken
                if by_sum:  # the summed gap moves a sphere locally: candidates within ``reach`` of it
                    allowed &= np.linalg.norm(points - points[chosen[j]], axis=1) <= reach
                best = _best_candidate(gaps, gap, order, allowed, now.max(), np.maximum(now, 0).sum(), by_sum)
                if best >= 0:
                    taken[chosen[j]], taken[best] = False, True
                    chosen[j] = best
                    moved = True
            if not moved:
                break
    return chosen


@dataclass(frozen=True)
class ElementCluster:
    """Particles of one element mesh in its local frame, and its buoyant part if any."""

    centres: np.ndarray  # (k, 3) local frame
    radii: np.ndarray  # (k,)
    yolk_centre: np.ndarray | None = None  # local frame
    yolk_radius: float = 0.0
    membrane_centre: np.ndarray | None = None  # local frame
    membrane_radius: float = 0.0  # inner room of the body around its centre (for the yolk)


def _layered_cover(gaps, points, shell, total: int, offset: float, tolerance, reach, enough, name="") -> np.ndarray:
    """Two layers through the element's thickness (its shell's axis of least spread): each half of the shell
    covered (``_cover``) by half the count of spheres centred at least ``offset`` × the half-thickness off the
    mid-plane, the deepest of the half first."""
    centre = shell.mean(axis=0)
    axis = np.linalg.eigh(np.cov((shell - centre).T))[1][:, 0]
    s_shell = (shell - centre) @ axis
    mid = 0.5 * (s_shell.max() + s_shell.min())
    half = 0.5 * float(np.ptp(s_shell))
    s_points = (points - centre) @ axis - mid
    chosen = []
    for side, count in ((1.0, (total + 1) // 2), (-1.0, total // 2)):
        cand = np.flatnonzero(side * s_points >= offset * half)
        if len(cand) == 0:
            raise ValueError(
                f"particle_layers 2: element mesh {name!r} is too thin for two layers at {len(points)} grid points "
                f"(none {offset:g} × its half-thickness {half:.3g} mm off its mid-plane); use particle_layers 1"
            )
        verts = np.flatnonzero(side * (s_shell - mid) >= 0.0)
        sub = np.ascontiguousarray(gaps[np.ix_(cand, verts)])
        deepest = np.array([np.argmin(sub.max(axis=1))], np.int64)
        picks = _cover(sub, points[cand], deepest, min(count, len(cand)), tolerance, reach, enough)
        chosen.extend(cand[picks])
    return np.asarray(chosen, np.int64)


# a layer's centres lie at least this share of the half-thickness off the mid-plane: the two layers then sit about
# half the thickness apart, so the grain can flatten 25 % (Tomita's strain at 0.2 N, via G) with its layers still
# apart; they meet near 50 %, where cooked rice fractures
LAYER_OFFSET = 0.5


def _body_and_yolk(mesh):
    faces = np.asarray(mesh.faces)
    parts = mesh.parts
    if parts is None or not np.any(parts == 1):
        return faces, None
    return faces[parts != 1], faces[parts == 1]


def element_cluster(mesh, count: int, cells: int = 24, quadratic: bool = True, layers: int = 1) -> ElementCluster:
    """Sphere packing of ``mesh`` with ``count`` particles (fewer only if the mesh is tiny) whose union
    covers its surface (``_cover``). ``quadratic``: spread through the core where the quadratic goal
    (SPEC §5) could not observe the cover's centres; a linear run can pass False for the best cover.
    ``layers`` 2: each half of the element through its thickness covered by half the particles
    (``_layered_cover``), so shape matching can flatten the cluster (the xpbd node's ``particle_layers``)."""
    import igl
    import trimesh

    from .collider import signed_distance_grid

    if count < 1:
        raise ValueError(f"element_cluster: count must be ≥ 1 particle, got {count}")
    body_faces, yolk_faces = _body_and_yolk(mesh)
    vertices = np.asarray(mesh.vertices)
    body = trimesh.Trimesh(vertices, body_faces, process=True)
    if not body.is_watertight:
        body = body.convex_hull  # documented repair: an open element mesh is packed by its hull
    lo, hi = body.bounds
    pitch = float((hi - lo).max()) / cells
    phi, origin, pitch = signed_distance_grid([body], lo - 2 * pitch, hi + 2 * pitch, pitch)
    depth = -phi
    if not depth.max() > 0:
        raise ValueError(f"element mesh {mesh.name or ''!r} has no interior at {pitch:.3g} resolution")
    # candidates: interior grid points at least half a cell deep (a thinner sphere is below what the grid
    # resolves, and a near-zero radius would set the solver's speed clamp); the deepest if none is
    idx = np.argwhere(depth >= min(0.5 * pitch, depth.max()))
    points = origin + idx * pitch
    depths = depth[tuple(idx.T)]
    shell = np.ascontiguousarray(body.vertices, np.float64)
    # φ is exact within 3 cells of the surface (``surface_band``); deeper, its distance transform reaches
    # the nearest outside grid point, up to a cell too far: measure those depths on the mesh, so every
    # sphere lies inside it
    grid_depths = depths.copy()
    far = np.flatnonzero(depths > 3.0 * pitch)
    faces = np.ascontiguousarray(body.faces, np.int64)
    depths[far] = np.sqrt(igl.point_mesh_squared_distance(points[far], shell, faces)[0])
    total = min(count, len(points))
    gaps = _gap_matrix(points, depths, shell)
    deepest = np.array([np.argmax(depths)], np.int64)
    # τ to 0.2 % of the length; a summed-gap swap moves up to 2 cells; a quarter cell is as covered as
    # the grid resolves (the rest of the count then spreads through the core: a round egg)
    tolerance, reach, enough = 0.05 * pitch, 2 * pitch, 0.25 * pitch
    if layers > 1:
        chosen = _layered_cover(gaps, points, shell, total, LAYER_OFFSET, tolerance, reach, enough, mesh.name or "")
    else:
        chosen = _cover(gaps, points, deepest, total, tolerance, reach, enough)
        chosen = _core_fill(points, grid_depths, chosen, total)  # the core as the former clusters chose it
    if layers == 1 and quadratic and total >= 10 and not _quadratic_observable(points[chosen]):
        # centres near one quadric surface (a round grain's lie on its axis): the quadratic goal would
        # fall back to linear; trade cover spheres for core points until it does not
        chosen, traded = _spread_through_core(gaps, points, depths, chosen)
        if traded:  # cover anew around the deepest and the core points traded in; kept if still observable
            again = _cover(gaps, points, chosen[: 1 + traded], total, tolerance, reach, enough)
            again = _core_fill(points, grid_depths, again, total)
            worst = gaps[again].min(axis=0).max()
            if _quadratic_observable(points[again]) and worst < gaps[chosen].min(axis=0).max():
                chosen = again
    centres = points[chosen]
    radii = depths[chosen]
    if yolk_faces is None:
        return ElementCluster(centres, radii)
    yolk_vertices = vertices[np.unique(yolk_faces)]
    yolk_centre = yolk_vertices.mean(axis=0)
    yolk_radius = float(np.linalg.norm(yolk_vertices - yolk_centre, axis=1).mean())
    body = vertices[np.unique(body_faces)]
    body_centre = body.mean(axis=0)
    membrane = float(np.linalg.norm(body - body_centre, axis=1).min())
    return ElementCluster(centres, radii, yolk_centre, yolk_radius, body_centre, membrane)


def matrix_to_quat(rotations: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations → (n, 4) quaternions w-x-y-z (scipy orthonormalises slightly off input)."""
    from scipy.spatial.transform import Rotation

    xyzw = Rotation.from_matrix(rotations).as_quat()
    return np.ascontiguousarray(xyzw[:, [3, 0, 1, 2]])
