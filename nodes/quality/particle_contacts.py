"""The ``particle_contacts`` node: how well a simulated pile has resolved its contacts, as one Table row.

A measure of the simulation's result that needs nothing from the solver's internals: the depth by
which particles of different elements still overlap (the XPBD contact constraint C = |xᵢ − xⱼ| − rᵢ − rⱼ ≥ 0,
SPEC §3, left unsatisfied), the pile's height and how fast its particles still move. A sweep of the
solver's substeps × iterations reads these as its accuracy metrics.
"""

from __future__ import annotations

import numpy as np

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, node
from nodegraph.values import Table

from ..values import ParticleState


def contact_depths(positions: np.ndarray, radii: np.ndarray, element: np.ndarray) -> np.ndarray:
    """Overlap depth rᵢ + rⱼ − |xᵢ − xⱼ| (> 0) of every overlapping pair of particles of different elements."""
    from scipy.spatial import cKDTree

    if len(positions) < 2:
        return np.zeros(0)
    pairs = cKDTree(positions).query_pairs(2.0 * float(radii.max()), output_type="ndarray")
    pairs = pairs[element[pairs[:, 0]] != element[pairs[:, 1]]]
    gap = np.linalg.norm(positions[pairs[:, 0]] - positions[pairs[:, 1]], axis=1)
    depth = radii[pairs[:, 0]] + radii[pairs[:, 1]] - gap
    return depth[depth > 0.0]


# the elements of the simulation it measures
@estimated_by(passes("particles"))
@node(
    "particle_contacts",
    inputs={"particles": In(ParticleState, "the simulation's particles (xpbd.particles)")},
    outputs={"stats": Out(Table, "one row: overlap depth between elements, pile height, particle speed")},
)
def particle_contacts(ctx, particles):
    """Residual contact overlap of a particle pile (SPEC §3 contact constraint), its height and speed."""
    positions = np.asarray(particles.positions, float)
    radii = np.asarray(particles.radii, float)
    depth = contact_depths(positions, radii, np.asarray(particles.element))
    r = float(radii.mean()) if len(radii) else 1.0
    z = positions[:, 2] if len(positions) else np.zeros(1)
    speed = np.linalg.norm(np.asarray(particles.velocities, float), axis=1) if len(positions) else np.zeros(1)
    return Table(
        {
            "penetration_max_r": np.array([depth.max() / r if len(depth) else 0.0]),
            "penetration_mean_r": np.array([depth.mean() / r if len(depth) else 0.0]),
            "overlapping_pairs": np.array([len(depth)]),
            "height_p95": np.array([float(np.percentile(z, 95) - z.min())]),
            "speed_mean": np.array([float(speed.mean())]),
            "particles": np.array([len(positions)]),
        }
    )
