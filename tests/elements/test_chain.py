"""The element chain: scatter → voxelise → distance field → expand → remesh → library (SPEC §1)."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.elements import distance_field, element_library, expand, remesh, sphere_scatter, voxelise
from nodes.elements.distance_fields import binary_field
from nodes.elements.grain_shapes import RICE_VARIETIES, volume_centroid
from nodes.elements.library_props import surface_distance
from nodes.elements.sphere_sampling import INSIDE, SURFACE
from nodes.elements.voxel_grid import grid_for, mesh_occupancy
from nodes.mesh_inside import inside_points, point_winding

from .conftest import as_trimesh, chain, digest


def test_scatter_places_surface_and_inside_spheres(japonica):
    spheres = sphere_scatter.call(seed=1, mesh=japonica, count=50, surface_share=0.6, radius_range=(0.1, 0.3))
    assert len(spheres) == 50 and (spheres.tags == SURFACE).sum() == 30
    assert ((spheres.radii >= 0.1) & (spheres.radii <= 0.3)).all()
    assert (point_winding(japonica.vertices, japonica.faces, spheres.centers[spheres.tags == INSIDE]) == 1).all()
    # surface centres lie on the mesh (area-weighted points of its triangles)
    on_surface = spheres.centers[spheres.tags == SURFACE]
    assert max(surface_distance(c, japonica.vertices, japonica.faces) for c in on_surface) < 1e-9
    assert sphere_scatter.call(seed=2, mesh=japonica, count=0).centers.shape == (0, 3)


def test_winding_occupancy_matches_exact_volume():
    from nodes.elements.grain_shapes import icosphere

    vertices, faces = icosphere(4)
    vertices = vertices * 2.0
    grid = grid_for(vertices.min(0), vertices.max(0), 96, None, 2)
    inside = mesh_occupancy(grid, vertices, faces)
    volume, _ = volume_centroid(vertices, faces)
    assert inside.sum() * grid.voxel_size**3 == pytest.approx(volume, rel=0.01)
    # a nested, outward shell (ikura yolk) stays inside
    nested = mesh_occupancy(grid, np.vstack([vertices, vertices * 0.5]), np.vstack([faces, faces + len(vertices)]))
    assert (nested == inside).all()


def test_grain_is_watertight_centred_and_expanded(japonica):
    _, _, field, grain = chain(japonica, seed=3, resolution=40, expansion=(1.2, 1.2))
    tm = as_trimesh(grain)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    _, centroid = volume_centroid(grain.vertices, grain.faces)
    assert np.allclose(centroid, 0.0, atol=1e-9)
    _, _, _, plain = chain(japonica, seed=3, resolution=40)
    assert tm.volume / as_trimesh(plain).volume == pytest.approx(1.2**3, rel=1e-6)  # eq. 6 is exact scaling
    assert grain.expansion == pytest.approx(1.2)
    assert np.ptp(grain.vertices[:, 0]) > np.ptp(grain.vertices[:, 1])  # long axis stays x


def test_exact_route_is_closer_than_binary(japonica):
    spheres = sphere_scatter.call(seed=4, mesh=japonica)
    volume = voxelise.call(mesh=japonica, spheres=spheres, resolution=48)
    exact = distance_field.call(volume=volume, mesh=japonica, spheres=spheres, method="exact")
    binary = distance_field.call(volume=volume, method="euclidean")
    # at cell centres next to the surface, the exact field is the signed distance to mesh ∪ spheres
    band = np.abs(exact.data) < volume.voxel_size
    centres = volume.cell_centers(band)
    d_sph = (spheres.radii - np.linalg.norm(centres[:, None] - spheres.centers[None], axis=2)).max(axis=1)
    sign = np.where(inside_points(japonica.vertices, japonica.faces, centres), 1.0, -1.0)
    d_mesh = sign * np.array([surface_distance(c, japonica.vertices, japonica.faces) for c in centres])
    assert np.allclose(exact.data[band], np.maximum(d_mesh, d_sph), atol=1e-6)
    assert set(np.unique(np.round(binary.data[volume.data] / volume.voxel_size, 6))) >= {1.0}
    # exact inradius is below the binary one (binary measures to outside cell centres)
    assert exact.data.max() < binary.data.max() + volume.voxel_size


def test_manhattan_is_at_least_euclidean():
    inside = np.zeros((20, 20, 20), bool)
    inside[3:17, 3:17, 3:17] = True
    e = binary_field(inside, 0.5, "euclidean")
    m = binary_field(inside, 0.5, "manhattan")
    assert (np.abs(m) >= np.abs(e) - 1e-6).all() and (np.abs(m) > np.abs(e) + 1e-6).any()
    assert e[10, 10, 10] == pytest.approx(0.5 * 7)  # eq. 5: 7 cells to the nearest outside cell


def test_same_seed_is_bit_identical(japonica):
    a = chain(japonica, seed=5, resolution=32)
    b = chain(japonica, seed=5, resolution=32)
    c = chain(japonica, seed=6, resolution=32)
    key = lambda r: digest(r[0].centers, r[0].radii, r[2].data, r[3].vertices, r[3].faces)  # noqa: E731
    assert key(a) == key(b)
    assert key(a) != key(c)


def test_target_faces_is_met_and_closed(japonica):
    _, _, _, grain = chain(japonica, seed=7, resolution=48, target_faces=800)
    tm = as_trimesh(grain)
    assert len(grain.faces) <= 800 * 1.15**3 and tm.is_watertight and tm.is_winding_consistent


def test_smoothing_keeps_the_grain_closed(japonica):
    _, _, _, grain = chain(japonica, seed=7, resolution=32, method="euclidean", smoothing=10)
    assert as_trimesh(grain).is_watertight


def test_library_props(japonica):
    grains = [chain(japonica, seed=s, resolution=32, expansion=(1.0, 1.5))[3] for s in range(3)]
    library = element_library.call(meshes=grains, kind="japonica")
    assert len(library) == 3 and library.kind == "japonica"
    for key in ("expansion", "volume", "circumradius", "inradius", "length", "width", "thickness"):
        assert library.props[key].shape == (3,)
    assert (library.props["inradius"] < library.props["circumradius"]).all()
    assert np.allclose(library.props["volume"], [as_trimesh(g).volume for g in grains])
    assert len(set(library.props["expansion"])) == 3 and (library.props["expansion"] <= 1.5).all()


def test_library_refuses_open_meshes(japonica):
    from nodegraph.values import Mesh

    broken = Mesh(japonica.vertices, japonica.faces[:-1])
    with pytest.raises(ValueError, match="not a closed"):
        element_library.call(meshes=[japonica, broken])
    with pytest.raises(ValueError, match="at least one"):
        element_library.call(meshes=[])


def test_variety_expansion(japonica):
    spheres = sphere_scatter.call(mesh=japonica, count=0)
    volume = voxelise.call(mesh=japonica, spheres=spheres, resolution=24)
    field = distance_field.call(volume=volume, method="euclidean")
    assert expand.call(field=field, variety=RICE_VARIETIES["indica"]).expansion == 1.2
    assert expand.call(field=field, variety=RICE_VARIETIES["japonica"]).expansion == 1.5
    drawn = {expand.call(seed=s, field=field).expansion for s in range(5)}
    assert len(drawn) == 5 and all(1.0 <= p <= 1.5 for p in drawn)


def test_element_far_from_origin(japonica):
    from nodegraph.values import Mesh
    from nodes.values import SphereSet

    spheres = sphere_scatter.call(seed=8, mesh=japonica)
    shift = np.array([1e5, -2e5, 3e4])
    far_mesh = Mesh(japonica.vertices + shift, japonica.faces)
    far_spheres = SphereSet(spheres.centers + shift, spheres.radii)
    near = voxelise.call(mesh=japonica, spheres=spheres, resolution=32)
    far = voxelise.call(mesh=far_mesh, spheres=far_spheres, resolution=32)
    assert (near.data == far.data).all()
    fn = distance_field.call(volume=near, mesh=japonica, spheres=spheres)
    ff = distance_field.call(volume=far, mesh=far_mesh, spheres=far_spheres)
    assert np.abs(fn.data - ff.data).max() < 1e-6
    grain_near = remesh.call(field=fn)
    grain_far = remesh.call(field=ff)
    assert np.abs(grain_near.vertices - grain_far.vertices).max() < 1e-6  # both centred


def test_ikura_through_the_chain():
    from nodes.elements import base_mesh

    egg = base_mesh.call(shape="ikura", diameter=4.0)
    volume = voxelise.call(mesh=egg, resolution=40)
    assert volume.data[tuple(np.array(volume.data.shape) // 2)]  # yolk centre is inside the solid
    grain = remesh.call(field=distance_field.call(volume=volume, mesh=egg))
    assert as_trimesh(grain).volume == pytest.approx(4 / 3 * np.pi * 2.0**3, rel=0.02)


@pytest.mark.parametrize("method", ["euclidean", "manhattan"])
def test_binary_offset_on_whole_voxels_stays_closed(japonica, method):
    spheres = sphere_scatter.call(mesh=japonica)
    volume = voxelise.call(mesh=japonica, spheres=spheres, resolution=32)
    field = distance_field.call(volume=volume, method=method)
    for cells in (-2, 1):  # the level hits field values exactly
        grain = remesh.call(field=field, level=float(np.float32(cells * volume.voxel_size)))
        assert as_trimesh(grain).is_watertight
