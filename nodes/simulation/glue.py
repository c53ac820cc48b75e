"""Glued grains: pressed sticky rice that holds its shape — SPEC §3 (clumping) and §5 (shape matching), issue 24.

``adhesion`` pulls near-touching particles together along their normal only, so it holds no shear: a
pressed onigiri set on its plate under gravity slid apart like a loose heap (63–78 % of its height kept).
Cooked rice pressed by hand is glued by its starch paste at every contact. Glued grains here are
lattice shape matching (Rivers & James 2007; Müller et al. 2005 §4.4 clusters): at the start of a run,
grains with particles closer than the capture radius (gap ≤ capture) are glued, and every grain gets a
region — its own particles and those of the grains glued to it — whose rest shape is where they stand
then. Each iteration every region is matched rigidly (best rotation of its current against its rest
shape, ``shape_matching.extract_rotation``) and each particle moves ``stiffness`` of the way to the mean
of its regions' goals. A region spans a grain's neighbourhood, so the weight of the pile reaches the
plate within the iterations a substep has (glued distance constraints, Jacobi-averaged over ≈ 13 bonds
per particle, carried it one bond per iteration: the draft onigiri kept 86 % of its height at 2
iterations and 99 % only at 8). A neighbour grain torn further than ``SolverSettings.glue_tear`` (one
particle radius) from its place in the region (mean over its particles) leaves that region for good: the
paste has torn. Contacts between glued grains tolerate the overlap the press left them
(``glued_allowance``). Iterations still bound the stiffness: the full-size onigiri keeps 98 % of its
height at 30 substeps and 94–96 % at 10–20 (docs/validation.md).
"""

from collections import namedtuple
from typing import NamedTuple

import numpy as np
from numba import njit, prange
from scipy.spatial import cKDTree

from .shape_matching import extract_rotation

# the regions as ``glue_match`` reads them (a named bundle: numba takes it as one argument)
RegionRows = namedtuple("RegionRows", "region_start link_own link_start member rest")


class GlueArrays(NamedTuple):
    """What the glue changes as its kernels take it: which links hold (``State.glued``), the regions' warm-started
    rotations (``State.glue_quats``) and each membership's goal (the solver's, NaN until matched)."""

    intact: np.ndarray  # (L,) bool
    quats: np.ndarray  # (m, 4)
    goal: np.ndarray  # (M, 3)


class GlueRule(NamedTuple):
    """What the glue kernels take of the settings (once per run, ``solver.XpbdSolver``)."""

    rot_iters: int  # iterations of the rotation extraction
    limit: float  # mm: ``glue_tear``, the mean distance from the goals at which a link tears
    stiffness: float  # share of the way to the goals per iteration (``SolverSettings.glue``)


class GlueMembers(NamedTuple):
    """Each particle's memberships (CSR ``pstart``, slots ``pslot``): what ``glue_pull`` reads."""

    pstart: np.ndarray  # (n + 1,)
    pslot: np.ndarray  # (M,)


class GlueFloors(NamedTuple):
    """Each particle's pressed glued partners and the regions' links: what ``glued_floors`` reads."""

    floor_start: np.ndarray  # (n + 1,)
    floor_partner: np.ndarray
    floor_depth: np.ndarray  # mm
    region_start: np.ndarray  # (m + 1,)
    link_grain: np.ndarray  # (L,)


class GluedEntries(NamedTuple):
    """Per entry of the neighbour lists: the link gluing its grains (−1: none), the overlap the press left it, and
    whether its grains are still glued (``glued_floors``, ``glued_allowance``)."""

    link: np.ndarray  # int64
    depth: np.ndarray
    stuck: np.ndarray  # bool


def glue_bonds(x, r, elem, n_moving: int, capture: float) -> np.ndarray:
    """Pairs (b, 2), i < j, of particles of different moving elements with gap ≤ ``capture`` at ``x``,
    in a deterministic order."""
    if n_moving < 2:
        return np.zeros((0, 2), np.int64)
    xm, rm = x[:n_moving], r[:n_moving]
    pairs = cKDTree(xm).query_pairs(2.0 * float(rm.max()) + capture, output_type="ndarray").astype(np.int64)
    pairs = pairs[elem[pairs[:, 0]] != elem[pairs[:, 1]]]
    gap = np.linalg.norm(xm[pairs[:, 0]] - xm[pairs[:, 1]], axis=1) - rm[pairs[:, 0]] - rm[pairs[:, 1]]
    pairs = pairs[gap <= capture]
    return np.ascontiguousarray(pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))])


def glued_regions(x, r, elem, start, n_moving: int, capture: float):
    """The regions of the grains glued at positions ``x`` (module docstring), or None when no two grains
    touch. Arrays: ``region_start`` (m + 1) CSR of the links of each region; links (a grain within a
    region) with ``link_grain``, ``link_own`` (the region's own grain: never torn) and ``link_start``, the
    CSR of their memberships; memberships ``member`` (particle), ``rest`` (its position at the start);
    ``pstart``, ``pslot``: the memberships of each particle, for the gather; ``floor_start``,
    ``floor_partner``, ``floor_depth``: per particle, the glued partners it overlaps and by how much
    (``glued_allowance``)."""
    pairs = glue_bonds(x, r, elem, n_moving, capture)
    if not len(pairs):
        return None
    m = len(start) - 1
    grains = np.unique(np.sort(elem[pairs], axis=1), axis=0)
    both = np.concatenate([grains, grains[:, ::-1]])
    both = both[np.lexsort((both[:, 1], both[:, 0]))]
    count = np.bincount(both[:, 0], minlength=m)
    nb_start = np.concatenate([[0], np.cumsum(count)])
    region_start = np.zeros(m + 1, np.int64)
    link_grain, link_own = [], []
    for g in range(m):
        link_grain.append(g)
        link_own.append(True)
        link_grain.extend(both[nb_start[g] : nb_start[g + 1], 1])
        link_own.extend([False] * int(count[g]))
        region_start[g + 1] = len(link_grain)
    link_grain = np.asarray(link_grain, np.int64)
    sizes = np.diff(start)[link_grain]
    link_start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    member = np.concatenate([np.arange(start[g], start[g + 1]) for g in link_grain]).astype(np.int64)
    pslot = np.argsort(member, kind="stable").astype(np.int64)
    pstart = np.zeros(len(x) + 1, np.int64)
    np.cumsum(np.bincount(member, minlength=len(x)), out=pstart[1:])
    ends = np.concatenate([pairs, pairs[:, ::-1]])
    depth = np.maximum(0.0, r[ends[:, 0]] + r[ends[:, 1]] - np.linalg.norm(x[ends[:, 0]] - x[ends[:, 1]], axis=1))
    pressed = depth > 0.0
    ends, depth = ends[pressed], depth[pressed]
    order = np.lexsort((ends[:, 1], ends[:, 0]))
    floor_start = np.zeros(len(x) + 1, np.int64)
    np.cumsum(np.bincount(ends[:, 0], minlength=len(x)), out=floor_start[1:])
    return {
        "floor_start": floor_start,
        "floor_partner": np.ascontiguousarray(ends[order, 1]),
        "floor_depth": np.ascontiguousarray(depth[order]),
        "region_start": region_start,
        "link_grain": link_grain,
        "link_own": np.asarray(link_own, np.bool_),
        "link_start": link_start,
        "member": member,
        "rest": np.ascontiguousarray(x[member], np.float64),
        "pstart": pstart,
        "pslot": pslot,
    }


BLOCK = 64  # regions per parallel task: one 3×3 scratch pair per block, none per region


@njit(cache=True)
def _match_region(x, w, regions, intact, quats, rot_iters, goal, torn_by, limit, reg, a, rot):
    """``glue_match`` for region ``reg``, with ``a`` and ``rot`` 3×3 scratch. Sums in scalars, in the order
    the per-region arrays summed them before (bytes unchanged), and no allocation per region: at 3,086
    regions × 2 iterations × 600 substeps the four small arrays each region allocated cost more than its sums."""
    region_start, link_own, link_start, member, rest = regions
    a0 = region_start[reg]
    a1 = region_start[reg + 1]
    glued = 0
    for link in range(a0, a1):
        if intact[link] and not link_own[link]:
            glued += 1
    if glued == 0:
        for s in range(link_start[a0], link_start[a1]):
            goal[s, 0] = np.nan
        return
    mass = 0.0
    cx = 0.0
    cy = 0.0
    cz = 0.0
    rx = 0.0
    ry = 0.0
    rz = 0.0
    for link in range(a0, a1):
        if not intact[link]:
            continue
        for s in range(link_start[link], link_start[link + 1]):
            i = member[s]
            mi = 1.0 / w[i]
            mass += mi
            cx += mi * x[i, 0]
            cy += mi * x[i, 1]
            cz += mi * x[i, 2]
            rx += mi * rest[s, 0]
            ry += mi * rest[s, 1]
            rz += mi * rest[s, 2]
    cx /= mass
    cy /= mass
    cz /= mass
    rx /= mass
    ry /= mass
    rz /= mass
    a00 = a01 = a02 = a10 = a11 = a12 = a20 = a21 = a22 = 0.0
    for link in range(a0, a1):
        if not intact[link]:
            continue
        for s in range(link_start[link], link_start[link + 1]):
            i = member[s]
            mi = 1.0 / w[i]
            px = mi * (x[i, 0] - cx)
            py = mi * (x[i, 1] - cy)
            pz = mi * (x[i, 2] - cz)
            qx = rest[s, 0] - rx
            qy = rest[s, 1] - ry
            qz = rest[s, 2] - rz
            a00 += px * qx
            a01 += px * qy
            a02 += px * qz
            a10 += py * qx
            a11 += py * qy
            a12 += py * qz
            a20 += pz * qx
            a21 += pz * qy
            a22 += pz * qz
    a[0, 0], a[0, 1], a[0, 2] = a00, a01, a02
    a[1, 0], a[1, 1], a[1, 2] = a10, a11, a12
    a[2, 0], a[2, 1], a[2, 2] = a20, a21, a22
    extract_rotation(a, quats[reg], rot_iters, rot)
    r00, r01, r02 = rot[0, 0], rot[0, 1], rot[0, 2]
    r10, r11, r12 = rot[1, 0], rot[1, 1], rot[1, 2]
    r20, r21, r22 = rot[2, 0], rot[2, 1], rot[2, 2]
    for link in range(a0, a1):
        if not intact[link]:
            for s in range(link_start[link], link_start[link + 1]):
                goal[s, 0] = np.nan
            continue
        for s in range(link_start[link], link_start[link + 1]):
            qx = rest[s, 0] - rx
            qy = rest[s, 1] - ry
            qz = rest[s, 2] - rz
            goal[s, 0] = cx + r00 * qx + r01 * qy + r02 * qz
            goal[s, 1] = cy + r10 * qx + r11 * qy + r12 * qz
            goal[s, 2] = cz + r20 * qx + r21 * qy + r22 * qz
    if torn_by:  # a neighbour further than the limit from its place in the fitted region tears off
        for link in range(a0, a1):
            if link_own[link] or not intact[link]:
                continue
            dev = 0.0
            for s in range(link_start[link], link_start[link + 1]):
                i = member[s]
                dx = goal[s, 0] - x[i, 0]
                dy = goal[s, 1] - x[i, 1]
                dz = goal[s, 2] - x[i, 2]
                dev += np.sqrt(dx * dx + dy * dy + dz * dz)
            if dev > limit * (link_start[link + 1] - link_start[link]):
                intact[link] = False
                for s in range(link_start[link], link_start[link + 1]):
                    goal[s, 0] = np.nan


@njit(cache=True, parallel=True)
def glue_match(state, model, regions, glue, rule, torn_by):
    """Match every region with a grain still glued to it rigidly: ``goal`` (M, 3) of each membership
    (NaN where its link is torn or its region has no glued neighbour left). With ``torn_by`` set, then
    tear every link whose particles stand, on average, more than ``limit`` (mm) from their goals: the
    region's shape, not its motion, decides (goals of the last iteration against predicted positions
    tore a falling onigiri apart). Each region writes only its own memberships, links and quaternion:
    race-free, the same at any thread count. ``state``: ``StateArrays`` (x), ``model``: ``ModelArrays`` (w),
    ``regions``: ``RegionRows``, ``glue``: ``GlueArrays``, ``rule``: ``GlueRule`` (rotation iterations, limit)."""
    x, w = state.x, model.w
    intact, quats, goal = glue.intact, glue.quats, glue.goal
    rot_iters, limit = rule.rot_iters, rule.limit
    m = len(regions.region_start) - 1
    for b in prange((m + BLOCK - 1) // BLOCK):
        a = np.empty((3, 3))
        rot = np.empty((3, 3))
        for reg in range(b * BLOCK, min(m, (b + 1) * BLOCK)):
            _match_region(x, w, regions, intact, quats, rot_iters, goal, torn_by, limit, reg, a, rot)


@njit(cache=True, parallel=True)
def glue_pull(state, members, glue, rule):
    """Move each awake particle ``stiffness`` of the way to the mean of its regions' goals:
    x_i += stiffness·(mean goal − x_i). ``state``: ``StateArrays`` (x, awake), ``members``: ``GlueMembers``,
    ``glue``: ``GlueArrays`` (goal), ``rule``: ``GlueRule`` (stiffness)."""
    x, awake = state.x, state.awake
    pstart, pslot = members.pstart, members.pslot
    goal, stiffness = glue.goal, rule.stiffness
    for i in prange(len(pstart) - 1):
        if not awake[i]:
            continue
        gx = 0.0
        gy = 0.0
        gz = 0.0
        count = 0
        for a in range(pstart[i], pstart[i + 1]):
            s = pslot[a]
            if goal[s, 0] == goal[s, 0]:
                gx += goal[s, 0]
                gy += goal[s, 1]
                gz += goal[s, 2]
                count += 1
        if count > 0:
            x[i, 0] += stiffness * (gx / count - x[i, 0])
            x[i, 1] += stiffness * (gy / count - x[i, 1])
            x[i, 2] += stiffness * (gz / count - x[i, 2])


@njit(cache=True, inline="always")
def _link_of(a, b, region_start, link_grain):
    """The link of grain b in grain a's region, or −1 (b was never glued to a)."""
    for link in range(region_start[a] + 1, region_start[a + 1]):  # the first link is a's own
        if link_grain[link] == b:
            return link
    return -1


@njit(cache=True, parallel=True)
def glued_floors(model, rows, floors, entries):
    """Per entry of the lists (row p: particle order[p]'s, ``spatial_hash.neighbour_lists``): the link that glues
    its two grains (``link``, −1 where none: never glued, the same grain, or a static particle) and the overlap the
    press left the pair (``depth``, 0 where it left none). Once per build of the lists: what ``glued_allowance``
    reads each substep (searching the floors and regions there took 3.2 ms of a 30 ms onigiri substep on one
    thread). ``model``: ``ModelArrays`` (elem), ``rows``: the lists' ``contact_constraints.PairRows``, ``floors``:
    ``GlueFloors``, ``entries``: ``GluedEntries`` (link, depth written)."""
    elem = model.elem
    nbr_start, nbr, half, order = rows.nbr_start, rows.nbr, rows.half, rows.order
    floor_start, floor_partner, floor_depth = floors.floor_start, floors.floor_partner, floors.floor_depth
    region_start, link_grain = floors.region_start, floors.link_grain
    link, depth = entries.link, entries.depth
    m = len(region_start) - 1
    for p in prange(len(nbr_start) - 1):
        i = order[p]
        for a in range(nbr_start[p], nbr_start[p + 1]):
            link[a] = -1
            depth[a] = 0.0
            j = nbr[a]
            if (not half and j < i) or elem[i] >= m or elem[j] >= m or elem[i] == elem[j]:
                continue
            link[a] = _link_of(elem[i], elem[j], region_start, link_grain)
            if link[a] < 0:
                continue
            for f in range(floor_start[i], floor_start[i + 1]):
                if floor_partner[f] == j:
                    depth[a] = floor_depth[f]
                    break


@njit(cache=True)
def glued_allowance(entries, glue, allowance):
    """Raise each listed pair's tolerated overlap (``contact_constraints``' allowance) to the overlap the
    press left it with while its grains stay glued (``link``, ``depth``: ``glued_floors``): the glue keeps the
    pressed shape, so contacts that pushed those overlaps apart only fought it (with the contacts' mass
    scaling by height that fight lifted a glued onigiri off its plate at 17 mm/s); a deeper overlap is still
    resolved. ``stuck`` ← the entry's grains are still glued (their friction takes the true masses:
    ``contact_constraints.PairEntries``).
    Serial: 0.2 ms for the onigiri's 286,000 entries, and a parallel loop costs ≈ 0.5 s more to compile.
    ``entries``: ``GluedEntries`` (link, depth; stuck written), ``glue``: ``GlueArrays`` (intact)."""
    link, depth, stuck = entries.link, entries.depth, entries.stuck
    glued = glue.intact
    for a in range(len(link)):
        k = link[a]
        stuck[a] = k >= 0 and glued[k]
        if stuck[a] and depth[a] > allowance[a]:
            allowance[a] = depth[a]
