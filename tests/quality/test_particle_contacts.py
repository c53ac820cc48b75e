"""particle_contacts: overlap between particles of different elements (the sweep's accuracy metric)."""

import numpy as np

from nodes.quality import particle_contacts
from nodes.values import ParticleState


def state(positions, element, radius=1.0):
    n = len(positions)
    return ParticleState(
        positions=np.asarray(positions, float),
        velocities=np.zeros((n, 3)),
        radii=np.full(n, radius),
        inv_mass=np.ones(n),
        element=np.asarray(element, np.int32),
    )


def test_overlap_between_elements_only():
    # 0–1: same element, deep (ignored); 1–2: elements 0 and 1, 0.5 apart → depth 1.5 r; 3 is far away
    particles = state([[0, 0, 0], [0.1, 0, 0], [0.6, 0, 0], [10, 0, 0]], [0, 0, 1, 2])
    table = particle_contacts.call(particles=particles)
    assert table.columns["overlapping_pairs"][0] == 2  # 0–2 (0.6 apart) and 1–2 (0.5 apart)
    assert np.isclose(table.columns["penetration_max_r"][0], 1.5)
    assert np.isclose(table.columns["penetration_mean_r"][0], (1.5 + 1.4) / 2)
    assert table.columns["particles"][0] == 4


def test_no_contact_no_overlap():
    table = particle_contacts.call(particles=state([[0, 0, 0], [3, 0, 0]], [0, 1]))
    assert table.columns["penetration_max_r"][0] == 0.0 and table.columns["overlapping_pairs"][0] == 0
