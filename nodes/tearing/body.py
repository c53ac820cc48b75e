"""An elastic surface body that springs back and tears — SPEC §5 (U §3.1–3.3).

Each step (U fig. 3.5): the goal of every vertex from its cluster's shape matching
(``shape_matching.shape_match_goals``, the xpbd node's goal maps), then U eq. 3.16–3.17,
``v += α(g − x)/Δt + Δt·f/m``, ``x += Δt·v``, then — only with tearing on — the break test and,
when an edge breaks, the split, relabel, re-cluster and capping (``tearing``, ``surface_mesh``).
``α = min(1, k·Δt²)`` from a stiffness ``k`` (1/s²): the same material at any step count, and
never past U's stable bound α ≤ 1.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..simulation.shape_matching import (
    LinearMoments,
    QuadraticMoments,
    quadratic_moments,
    rest_moments,
    shape_match_goals,
)
from . import tearing
from .surface_mesh import SurfaceMesh, fan_caps


@dataclass(frozen=True)
class BodySettings:
    """Per-step settings: substep ``h`` (s), stiffness (1/s²), β and goal kind (SPEC §5), rotation
    iterations (Müller 2016), damping (1/s), and the tearing effect with its rule and threshold."""

    h: float
    stiffness: float = 1e4
    beta: float = 0.0
    quadratic: bool = False
    rotation_iterations: int = 4
    damping: float = 0.0
    tearing: bool = False
    threshold: float = 3.0
    rule: str = "vertex"

    def __post_init__(self):
        if not self.h > 0 or not self.stiffness >= 0:
            raise ValueError(f"step h = {self.h} and stiffness = {self.stiffness}: need h > 0, stiffness ≥ 0")
        if self.rule not in tearing.RULES:
            raise ValueError(f"tear rule {self.rule!r}; allowed: {', '.join(tearing.RULES)}")
        if not self.threshold > 1.0:
            raise ValueError(f"tear threshold {self.threshold}: must exceed 1 (× rest length)")

    @property
    def alpha(self) -> float:
        """U eq. 3.16's α = min(1, k·h²)."""
        return min(1.0, self.stiffness * self.h * self.h)


@njit(cache=True)
def integrate(x, v, goals, accel, moving, alpha, h, keep):
    """U eq. 3.16–3.17: v += α(g − x)/h + h·a, v *= keep (damping), x += h·v; held vertices stay."""
    for i in range(x.shape[0]):
        if not moving[i]:
            v[i, :] = 0.0
            continue
        for k in range(3):
            v[i, k] = (v[i, k] + alpha * (goals[i, k] - x[i, k]) / h + h * accel[i, k]) * keep
            x[i, k] += h * v[i, k]


class ElasticBody:
    """Vertices sorted by cluster (struct of arrays), their surface mesh and per-cluster rest data.

    ``calls`` counts what ran (``shape_matching``, ``integrate``, ``tear_check``, ``tear``): without the
    tearing effect the tear entries stay 0.
    """

    def __init__(self, vertices, faces, mass: float, settings: BodySettings, accel=None, moving=None):
        x = np.ascontiguousarray(vertices, dtype=np.float64)
        n = len(x)
        if n == 0 or not np.all(np.isfinite(x)):
            raise ValueError("vertices: need a non-empty set of finite positions")
        if not mass > 0:
            raise ValueError(f"mass {mass}: must be > 0")
        self.settings = settings
        self.mesh = SurfaceMesh.from_faces(faces, n)
        self.x = x.copy()
        self.x0 = x.copy()
        self.v = np.zeros_like(x)
        self.accel = np.zeros_like(x) if accel is None else np.array(accel, dtype=np.float64)
        self.moving = np.ones(n, bool) if moving is None else np.array(moving, dtype=bool)
        self.inv_mass = np.full(n, n / mass)
        self.goals = np.empty_like(x)
        self.calls: Counter[str] = Counter()
        self.tears = 0  # tear events (steps at which at least one edge broke)
        self.broken_edges = 0
        self._recluster(np.zeros(n, np.int64), np.array([[1.0, 0.0, 0.0, 0.0]]))

    @property
    def n_clusters(self) -> int:
        return len(self.start) - 1

    def _recluster(self, old_cluster: np.ndarray, old_quats: np.ndarray, split: np.ndarray | None = None) -> None:
        """Sort vertices by connected component and rebuild rest data (U §3.2.2 steps 3–4); a new cluster
        warm-starts its rotation from the cluster its first vertex came from. With ``split`` (per vertex:
        its old vertex was split, so its mass was shared), a cluster made of one old cluster's unsplit
        vertices, as many as it had, keeps that cluster's rest data: tearing out one fan then costs
        two clusters' moments, not all."""
        order, start = tearing.cluster_order(self.mesh)
        inverse = np.empty_like(order)
        inverse[order] = np.arange(len(order))
        per_vertex = ("x", "x0", "v", "accel", "moving", "inv_mass") + (() if split is None else ("q_rest", "qt"))
        for name in per_vertex:
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[order]))
        old_cluster = old_cluster[order]
        first = old_cluster[start[:-1]]
        m = self.mesh
        self.mesh = SurfaceMesh(inverse[m.faces], m.twin, m.cracked, m.n_vertices)
        count = len(start) - 1
        if split is None:
            changed = np.ones(count, bool)
            self.q_rest, self.qt = np.zeros_like(self.x), np.zeros((len(self.x), 9))
            self.aqq_pinv, self.null_proj = np.zeros((count, 3, 3)), np.zeros((count, 3, 3))
            self.qpinv, self.quadratic = np.zeros((count, 9, 9)), np.zeros(count, np.bool_)
        else:
            one_source = np.minimum.reduceat(old_cluster, start[:-1]) == np.maximum.reduceat(old_cluster, start[:-1])
            same = one_source & (np.diff(start) == np.diff(self.start)[first])
            changed = ~same | np.logical_or.reduceat(split[order], start[:-1])
            self.aqq_pinv, self.null_proj = self.aqq_pinv[first], self.null_proj[first]
            self.qpinv, self.quadratic = self.qpinv[first], self.quadratic[first]
        self.start = start
        self.cluster = np.repeat(np.arange(count), np.diff(start))
        self._rest_data(np.flatnonzero(changed))
        self.quats = np.ascontiguousarray(old_quats[first])
        self.rest_length = np.linalg.norm(self.x0[self.mesh.origin] - self.x0[self.mesh.dest], axis=1)
        self._ratio = np.empty(len(self.mesh.twin))
        watched = tearing.watched_edges(self.mesh, self.settings.rule)
        self._watched = (self.mesh.origin[watched], self.mesh.dest[watched], self.rest_length[watched])
        self.loop_start, self.loop = self.mesh.boundary_loops()

    def _rest_data(self, clusters: np.ndarray) -> None:
        """q_i = x⁰_i − x⁰_cm, A_qq⁺ and its null projector, and the quadratic moments (SPEC §5) of
        ``clusters``, through the xpbd node's ``rest_moments`` / ``quadratic_moments``."""
        if len(clusters) == 0:
            return
        rows = np.concatenate([np.arange(self.start[c], self.start[c + 1]) for c in clusters])
        sizes = np.diff(self.start)[clusters]
        sub_start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        mass = 1.0 / self.inv_mass[rows]
        cm0 = np.add.reduceat(self.x0[rows] * mass[:, None], sub_start[:-1], axis=0)
        cm0 /= np.add.reduceat(mass, sub_start[:-1])[:, None]
        q = self.x0[rows] - np.repeat(cm0, sizes, axis=0)
        self.q_rest[rows] = q
        self.aqq_pinv[clusters], self.null_proj[clusters] = rest_moments(q, self.inv_mass[rows], sub_start)
        if self.settings.quadratic:
            qt, qpinv, quadratic = quadratic_moments(q, self.inv_mass[rows], sub_start)
            self.qt[rows], self.qpinv[clusters], self.quadratic[clusters] = qt, qpinv, quadratic

    def compute_goals(self) -> None:
        """Every vertex's goal g_i from its cluster (SPEC §5) into ``self.goals``."""
        s = self.settings
        self.calls["shape_matching"] += 1
        shape_match_goals(
            self.x,
            self.inv_mass,
            self.q_rest,
            self.start,
            self.quats,
            LinearMoments(self.aqq_pinv, self.null_proj),
            s.beta,
            s.rotation_iterations,
            QuadraticMoments(self.qt, self.qpinv, self.quadratic),
            self.goals,
        )

    def step(self) -> bool:
        """One time step (U fig. 3.5); returns True when the body tore in it."""
        s = self.settings
        self.compute_goals()
        self.calls["integrate"] += 1
        integrate(self.x, self.v, self.goals, self.accel, self.moving, s.alpha, s.h, np.exp(-s.damping * s.h))
        if not s.tearing:
            return False
        self.calls["tear_check"] += 1
        if tearing.largest_stretch(self.x, *self._watched) <= s.threshold:
            return False
        m = self.mesh
        tearing.stretch_ratios(self.x, m.origin, m.dest, self.rest_length, self._ratio)
        broken = tearing.broken_half_edges(m, self._ratio, s.threshold, s.rule)
        broken = (m.twin >= 0) & ~m.cracked & (broken | broken[np.maximum(m.twin, 0)])  # glued pairs, both halves
        if not broken.any():
            return False
        self.tear(broken)
        return True

    def tear(self, broken: np.ndarray) -> None:
        """Split along ``broken`` glued half-edge pairs (both halves flagged), relabel, re-cluster and
        cap (U §3.2.3). A vertex split into c copies gives each 1/c of its mass (same velocity), so the
        split conserves mass, momentum and kinetic energy."""
        self.calls["tear"] += 1
        self.tears += 1
        self.broken_edges += int(np.count_nonzero(broken)) // 2
        mesh, source = self.mesh.cut(broken)
        for name in ("x", "x0", "v", "accel", "moving", "inv_mass", "q_rest", "qt"):
            setattr(self, name, getattr(self, name)[source])
        copies = np.bincount(source)[source]
        self.inv_mass = self.inv_mass * copies
        self.goals = np.empty_like(self.x)
        self.mesh = mesh
        self._recluster(self.cluster[source], self.quats, split=copies > 1)

    def cap_positions(self) -> np.ndarray:
        """Centroid vertex of each opening (U §3.2.3's fan centre), following its rim. (L, 3)."""
        if len(self.loop) == 0:
            return np.zeros((0, 3))
        sums = np.add.reduceat(self.x[self.loop], self.loop_start[:-1], axis=0)
        return sums / np.diff(self.loop_start)[:, None]

    def closed_surface(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vertices (body, then cap centres), faces (mesh, then caps) and the cluster of each vertex."""
        n = len(self.x)
        caps = fan_caps(self.loop_start, self.loop, n)
        vertices = np.concatenate([self.x, self.cap_positions()])
        cluster = np.concatenate([self.cluster, self.cluster[self.loop[self.loop_start[:-1]]]])
        return vertices, np.concatenate([self.mesh.faces, caps]), cluster

    def pieces(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Each cluster with faces as its own closed mesh (vertices, faces); lone vertices have none."""
        vertices, faces, cluster = self.closed_surface()
        face_cluster = cluster[faces[:, 0]]
        out = []
        for c in range(self.n_clusters):
            f = faces[face_cluster == c]
            if len(f) == 0:
                continue
            used, local = np.unique(f, return_inverse=True)
            out.append((vertices[used], local.reshape(-1, 3)))
        return out

    def energy(self) -> float:
        """U's discrete invariant Σ m (α|u|² − α u·w + |w|²)/(2h²), u = x − g, w = h·v: constant for a
        fixed goal (spectral radius 1, U eq. 3.18), so its growth without external work is instability.
        Computed on a copy of the rotation warm starts, so it does not change the run."""
        s = self.settings
        quats = self.quats.copy()
        goals = np.empty_like(self.x)
        shape_match_goals(
            self.x,
            self.inv_mass,
            self.q_rest,
            self.start,
            quats,
            LinearMoments(self.aqq_pinv, self.null_proj),
            s.beta,
            s.rotation_iterations,
            QuadraticMoments(self.qt, self.qpinv, self.quadratic),
            goals,
        )
        u = self.x - goals
        w = s.h * self.v
        a = s.alpha
        per = a * (u * u).sum(1) - a * (u * w).sum(1) + (w * w).sum(1)
        return float((per / self.inv_mass).sum() / (2 * s.h * s.h))
