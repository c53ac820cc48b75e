"""Shared helpers for the placement tests: rice-like elements made here (not by issue 3's nodes)."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from nodegraph.values import Mesh
from nodes.values import ElementLibrary


def ellipsoid(semi_axes, subdivisions=3) -> Mesh:
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    mesh.apply_scale(semi_axes)
    return Mesh.from_trimesh(mesh, name="ellipsoid")


def rice_library(kind="rice", variants=2, refine_range=1.0) -> ElementLibrary:
    """Rice-like ellipsoids with circumscribed radius 1.1 (S's grain), slightly different per variant."""
    meshes = tuple(ellipsoid((1.1, 0.64 - 0.03 * v, 0.44 + 0.02 * v)) for v in range(variants))
    return ElementLibrary(kind, meshes, refine_range=refine_range)


def digest(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


@pytest.fixture(scope="session")
def rice():
    return rice_library()


@pytest.fixture(scope="session")
def small_onigiri():
    from nodes.shapes import shape

    return shape.call(kind="onigiri", size=8.0, resolution=4)["mesh"]
