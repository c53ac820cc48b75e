"""The shapes issue 17's scenes add: a nigiri block with its open-top tray mould, and shapes moved by ``offset``."""

import numpy as np
import trimesh

from nodes.shapes import shape


def _tm(mesh):
    return trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)


def test_block_is_a_closed_rounded_block_inside_its_open_tray():
    out = shape.call(kind="block", extents=(50.0, 23.0, 19.0), exponent=4.0, wall=2.0)
    block, tray = _tm(out["mesh"]), _tm(out["container"])
    assert block.is_watertight and block.volume > 0 and tray.is_watertight and tray.volume > 0
    assert np.allclose(block.bounds, [[-25.0, -11.5, -9.5], [25.0, 11.5, 9.5]], atol=1e-6)
    box = 50.0 * 23.0 * 19.0
    assert 0.7 * box < block.volume < box  # rounder than a box, fuller than the ellipsoid (π/6 of it)
    assert np.allclose(tray.bounds, [[-27.0, -13.5, -11.5], [27.0, 13.5, 9.5]], atol=1e-6)  # rim at the top
    # walls and floor 2 mm thick around the block's bounding box, open at the top
    assert np.isclose(tray.volume, 54.0 * 27.0 * 21.0 - 50.0 * 23.0 * 19.0)


def test_offset_moves_the_shape_and_its_container():
    still = shape.call(kind="bowl", size=20.0, depth=10.0, mound=2.0, resolution=2)
    moved = shape.call(kind="bowl", size=20.0, depth=10.0, mound=2.0, resolution=2, offset=(1.0, -2.0, 3.0))
    for port in ("mesh", "container"):
        assert np.allclose(moved[port].vertices, still[port].vertices + [1.0, -2.0, 3.0])
