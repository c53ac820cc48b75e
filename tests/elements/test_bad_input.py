"""Bad input gives a clear error, never a crash deep in numpy or a silent wrong mesh (issue 3)."""

from __future__ import annotations

import numpy as np
import pytest

from nodegraph.params import ParamValueError
from nodes.elements import distance_field, expand, remesh, sphere_scatter, voxelise
from nodes.values import SphereSet


@pytest.mark.parametrize("resolution", [1, 100_000])
def test_resolution_out_of_range_is_refused_by_the_declaration(resolution):
    with pytest.raises(ParamValueError):
        voxelise.resolve_params({"resolution": resolution})


def test_resolution_limits_in_the_kernel(japonica):
    from nodes.elements.voxel_grid import grid_for

    lo, hi = japonica.bounds
    with pytest.raises(ValueError, match="too small"):
        grid_for(lo, hi, 1, None, 3)
    with pytest.raises(ValueError, match="exceeds the limit"):
        grid_for(lo, hi, 100_000, None, 3)
    with pytest.raises(ValueError, match="exceeds the limit"):
        voxelise.call(mesh=japonica, voxel_size=1e-4)


def test_zero_radius_is_refused(japonica):
    with pytest.raises(ParamValueError):
        sphere_scatter.resolve_params({"radius_range": (0.0, 0.3)})
    spheres = SphereSet([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [0.3, 0.0])
    with pytest.raises(ValueError, match="radii are ≤ 0"):
        voxelise.call(mesh=japonica, spheres=spheres)


def test_nan_sphere_is_refused(japonica):
    spheres = SphereSet([[0.0, np.nan, 0.0]], [0.3])
    with pytest.raises(ValueError, match="NaN"):
        voxelise.call(mesh=japonica, spheres=spheres)


def test_spheres_that_cover_nothing(japonica):
    tiny = SphereSet([[0.0, 0.0, 0.0]], [1e-4])  # far smaller than a cell: no cell centre inside
    with pytest.raises(ValueError, match="volume is empty"):
        voxelise.call(spheres=tiny, voxel_size=0.5)
    with pytest.raises(ValueError, match="nothing to voxelise"):
        voxelise.call()


def test_spheres_away_from_the_mesh_make_a_clear_error(japonica):
    loose = SphereSet([[20.0, 0.0, 0.0]], [0.5])
    with pytest.raises(ValueError, match="separate pieces"):
        voxelise.call(mesh=japonica, spheres=loose, resolution=64)


def test_exact_route_without_geometry(japonica):
    volume = voxelise.call(mesh=japonica, resolution=16)
    with pytest.raises(ValueError, match="needs the mesh"):
        distance_field.call(volume=volume, method="exact")


def test_level_without_surface_or_cut_by_the_grid(japonica):
    volume = voxelise.call(mesh=japonica, resolution=24, padding=1)
    field = distance_field.call(volume=volume, mesh=japonica)
    with pytest.raises(ValueError, match="outside the field's range"):
        remesh.call(field=field, level=50.0)
    with pytest.raises(ValueError, match="edge of the grid"):
        remesh.call(field=field, level=-0.5)


def test_expansion_range_order_is_checked():
    assert expand.check(expand.resolve_params({"expansion": (1.5, 1.0)}))
    assert not expand.check(expand.resolve_params({"expansion": (1.0, 1.5)}))
