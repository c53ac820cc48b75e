"""Particle clusters (``nodes/simulation/clusters.py``): spheres inside the element whose union reaches its
surface (issue 17: a core-only packing let meshes settle ≈ 15 % of a length into each other)."""

from __future__ import annotations

import numpy as np
from xpbd_scenes import grain_mesh, ikura_mesh

from nodes.placement.medial_spheres import distance_to_surface, union_fit
from nodes.simulation.clusters import element_cluster


def test_cluster_spheres_reach_the_surface_and_stay_inside():
    mesh = grain_mesh()
    for count, gap in ((8, 0.08), (16, 0.05)):
        cluster = element_cluster(mesh, count)
        assert len(cluster.radii) == count and len(np.unique(cluster.centres, axis=0)) == count
        fit = union_fit(mesh.vertices, mesh.faces, cluster.centres, cluster.radii)
        # the former core-only packing (points ≥ half the deepest depth): gap_max 0.106 at 8 here
        assert fit["gap_max"] <= gap, (count, fit)
        surface = distance_to_surface(cluster.centres, mesh.vertices.astype(float), mesh.faces.astype(np.int64))
        assert np.all(cluster.radii <= surface + 0.1)  # radius = depth on the grid: inside within 2 % of a length


def test_egg_cluster_ignores_the_yolk():
    cluster = element_cluster(ikura_mesh(3.5), 8)
    assert cluster.radii.max() > 3.0  # the membrane's inside, not the yolk's
    assert cluster.yolk_radius > 0 and cluster.membrane_radius > cluster.yolk_radius
