"""The colliders' distance grid (``collider.signed_distance_grid``, SPEC §3): its exact band near the surface is
computed in blocks of rows on threads (``surface_band_rows``), each row seeing the faces in one order, so any split
gives the bits of one pass; the faces' plane slab only passes over points farther than the band."""

from __future__ import annotations

import igl
import numba
import numpy as np
import pytest
import trimesh
from scene_builders import bowl_mesh

from nodes.simulation import collider
from nodes.simulation.collider import free_space_field, signed_distance_grid, signed_field, surface_band_rows

BAND_CELLS = 3.0


def _bowl_band(pitch=0.45):
    """A thin bowl (tilted and flat faces, edges and vertices everywhere) and its grid."""
    mesh = bowl_mesh(radius=8.0, wall=0.7, rim=0.3, segments=24)
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=True)
    vertices, faces = np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64)
    origin = tm.bounds[0] - 2.0
    shape = tuple(int(s) for s in np.ceil((tm.bounds[1] + 2.0 - origin) / pitch).astype(int) + 1)
    return vertices, faces, np.asarray(tm.face_normals, float), origin, pitch, shape


def _rows(args, blocks):
    vertices, faces, normals, origin, pitch, shape = args
    dist, align = np.full(shape, np.inf), np.zeros(shape)
    for first, last in blocks:
        surface_band_rows(vertices, faces, normals, origin, pitch, BAND_CELLS * pitch, first, last, dist, align)
    return dist


def test_row_blocks_give_the_bits_of_one_pass():
    """Rows computed in blocks, in any order, equal one pass over all rows bit for bit (the threads' split in
    ``surface_band``); a block writes nothing outside its rows."""
    args = _bowl_band()
    n = args[5][0]
    whole = _rows(args, [(0, n)])
    cuts = [0, 1, 7, n // 2, n // 2 + 1, n - 3, n]
    blocks = list(zip(cuts[:-1], cuts[1:]))
    assert _rows(args, blocks[::-1]).tobytes() == whole.tobytes()
    alone = _rows(args, [(7, n // 2)])
    assert np.isinf(alone[:7]).all() and np.isinf(alone[n // 2 :]).all()
    assert alone[7 : n // 2].tobytes() == whole[7 : n // 2].tobytes()


def test_band_is_every_grid_point_within_it_at_its_exact_distance():
    """No point within the band is passed over by the plane-slab test: the band holds exactly the grid points
    nearer the surface than 3 cells, each at its distance to the mesh (libigl's, to rounding)."""
    vertices, faces, normals, origin, pitch, shape = args = _bowl_band()
    dist = _rows(args, [(0, shape[0])])
    points = origin + np.argwhere(np.ones(shape, bool)) * pitch
    exact = np.sqrt(igl.point_mesh_squared_distance(points, vertices, faces)[0]).reshape(shape)
    band = BAND_CELLS * pitch
    assert np.isfinite(dist[exact < band - 1e-9]).all()
    assert np.isinf(dist[exact > band + 1e-9]).all()
    finite = np.isfinite(dist)
    assert np.abs(dist[finite] - exact[finite]).max() < 1e-9


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="numba has one thread: nothing to compare")
def test_field_does_not_depend_on_the_thread_count():
    """φ (band, inside split, distance transforms) is the same bits on one thread and two."""
    mesh = bowl_mesh(radius=8.0, wall=0.7, rim=0.3, segments=24)
    threads = numba.get_num_threads()
    fields = []
    try:
        for count in (1, 2):
            numba.set_num_threads(count)
            fields.append(signed_distance_grid([mesh], np.array([-10.0, -10, -10]), np.array([10.0, 10, 4]), 0.3)[0])
    finally:
        numba.set_num_threads(threads)
    assert fields[0].tobytes() == fields[1].tobytes()


def test_a_moulds_field_is_the_negated_solid_bit_for_bit():
    """``sign`` −1 (a mould: its inside is the free space) gives −1 × the solid's φ in the same pass, bit for bit
    (``free_space_field`` no longer negates a copy of the grid)."""
    mesh = bowl_mesh(radius=8.0, wall=0.7, rim=0.3, segments=24)
    lo, hi = np.array([-10.0, -10, -10]), np.array([10.0, 10, 4])
    solid = signed_distance_grid([mesh], lo, hi, 0.3)[0]
    mould = signed_distance_grid([mesh], lo, hi, 0.3, sign=-1.0)[0]
    assert mould.tobytes() == (-1.0 * solid).tobytes()
    free, _, _ = free_space_field([], [mesh], lo, hi, 0.3)
    assert free.tobytes() == mould.tobytes()


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="numba has one thread: nothing to compare")
def test_signed_field_on_threads_gives_the_bits_of_one_pass(monkeypatch):
    """The signing pass over blocks of rows on threads (a large grid) equals one pass on one thread."""
    rng = np.random.default_rng(3)
    shape = (37, 11, 13)
    dist = np.where(rng.random(shape) < 0.3, rng.random(shape), np.inf)
    inside = rng.random(shape) < 0.5
    far = rng.random(shape).astype(np.float32)
    one = signed_field(dist, inside, far, -1.0)  # small: one thread
    monkeypatch.setattr(collider, "THREADED_POINTS", 0)
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(2)
        two = signed_field(dist, inside, far, -1.0)
    finally:
        numba.set_num_threads(threads)
    assert one.tobytes() == two.tobytes()
    expected = np.where(np.isfinite(dist), dist, far)
    assert one.tobytes() == (-1.0 * np.where(inside, -expected, expected)).tobytes()


def test_one_multi_label_transform_gives_the_bits_of_the_two_binary_ones(monkeypatch):
    """The far field is one distance transform per grid, of the labels inside 1 / outside 2; it equals, bit for bit,
    the depth of the inside (``edt`` of ``inside``) inside and the clearance (``edt`` of ``~inside``) outside, as the
    two transforms it replaced: a solid touching the grid's border, a thin slab, no inside at all, noise."""
    import edt

    calls = []
    transform = edt.edt
    monkeypatch.setattr(edt, "edt", lambda *args, **kwargs: calls.append(args) or transform(*args, **kwargs))
    signed_distance_grid(
        [bowl_mesh(radius=8.0, wall=0.7, rim=0.3, segments=24)], -np.full(3, 10.0), np.full(3, 10.0), 0.5
    )
    assert len(calls) == 1
    monkeypatch.setattr(edt, "edt", transform)
    rng = np.random.default_rng(5)
    border = np.zeros((30, 25, 20), bool)
    border[:10] = True
    slab = np.zeros((10, 40, 40), bool)
    slab[:, :, 18:21] = True
    for inside in (border, slab, np.zeros((9, 8, 7), bool), rng.random((33, 27, 19)) < 0.5):
        for pitch in (1.0, 0.37):
            far = edt.edt(2 - inside.view(np.uint8), anisotropy=(pitch,) * 3, parallel=2)
            depth = edt.edt(inside, anisotropy=(pitch,) * 3, parallel=2)
            clearance = edt.edt(~inside, anisotropy=(pitch,) * 3, parallel=2)
            assert far[inside].tobytes() == depth[inside].tobytes()
            assert far[~inside].tobytes() == clearance[~inside].tobytes()
