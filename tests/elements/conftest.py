"""Shared helpers for the element-node tests: call nodes directly, as the engine would."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.elements import base_mesh, distance_field, expand, remesh, sphere_scatter, voxelise


def chain(mesh, seed=0, resolution=32, method="exact", expansion=(1.0, 1.0), **remesh_params):
    """scatter → voxelise → distance_field → expand → remesh for one grain."""
    spheres = sphere_scatter.call(seed=seed, mesh=mesh)
    volume = voxelise.call(mesh=mesh, spheres=spheres, resolution=resolution)
    field = distance_field.call(volume=volume, mesh=mesh, spheres=spheres, method=method)
    grown = expand.call(seed=seed, field=field, expansion=expansion)
    return spheres, volume, field, remesh.call(field=grown, **remesh_params)


def as_trimesh(mesh):
    import trimesh

    return trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)


def digest(*arrays) -> str:
    import hashlib

    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


@pytest.fixture(scope="session")
def japonica():
    return base_mesh.call()
