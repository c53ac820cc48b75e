"""Kernels see one kind of array whether their input is a frozen node output or a fresh array, so numba
compiles each of them once (issue 27: four kernels compiled twice, ≈ 15 s of a first run)."""

import numpy as np
import trimesh

from nodes.kernel_arrays import kernel_array
from nodes.mesh_inside import inside_columns
from nodes.placement.candidates import volume_candidates


def test_kernel_array_copies_only_what_a_kernel_cannot_take():
    fresh = np.zeros((4, 3))
    assert kernel_array(fresh) is fresh
    frozen = np.zeros((4, 3))
    frozen.flags.writeable = False
    taken = kernel_array(frozen)
    assert taken.flags.writeable and taken.flags.c_contiguous and np.array_equal(taken, frozen)
    assert kernel_array(np.zeros((3, 4)).T).flags.c_contiguous
    assert kernel_array(np.zeros((2, 3), np.int32), np.int64).dtype == np.int64


def test_a_frozen_mesh_and_a_fresh_one_share_one_compiled_inside_test():
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    vertices, faces = np.array(box.vertices, np.float64), np.array(box.faces, np.int64)
    axes = [np.linspace(-0.4, 0.4, 3)] * 3
    inside_columns(vertices, faces, *axes)  # a fresh mesh, as the collider passes it
    vertices.flags.writeable = False  # a node output, as the placement nodes get it
    faces.flags.writeable = False
    points, _ = volume_candidates(vertices, faces, 0.25, np.random.default_rng(1))
    assert len(points) > 0
    assert len(inside_columns.signatures) == 1
