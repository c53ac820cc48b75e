"""Shared helpers for the element-node tests: call nodes directly, as the engine would."""

from __future__ import annotations

import numpy as np
import pytest

from nodegraph import Context
from nodes.elements import base_mesh, distance_field, expand, remesh, sphere_scatter, voxelise


def run(spec, seed=0, **given):
    """Call a node with validated parameters (defaults filled) and the given inputs."""
    inputs = {k: v for k, v in given.items() if k in spec.inputs}
    values = spec.resolve_params({k: v for k, v in given.items() if k not in spec.inputs})
    return spec(Context.standalone(node_type=spec.type_name, seed=seed), **inputs, **values)


def chain(mesh, seed=0, resolution=32, method="exact", expansion=(1.0, 1.0), **remesh_params):
    """scatter → voxelise → distance_field → expand → remesh for one grain."""
    spheres = run(sphere_scatter, seed, mesh=mesh)
    volume = run(voxelise, mesh=mesh, spheres=spheres, resolution=resolution)
    field = run(distance_field, volume=volume, mesh=mesh, spheres=spheres, method=method)
    grown = run(expand, seed, field=field, expansion=expansion)
    return spheres, volume, field, run(remesh, field=grown, **remesh_params)


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
    return run(base_mesh)
