"""The value codec: deterministic bytes, exact round trips, no pickle."""

import numpy as np
import pytest

from nodegraph import codec
from nodegraph.values import Mesh, Table
from nodes.values import ElementLibrary, Placement


def tetra(name=""):
    return Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], name=name)


def test_round_trip_is_exact_and_bytes_are_stable():
    lib = ElementLibrary(
        "rice", (tetra("a"), tetra("b")), props={"p": np.array([1.2, 1.5]), "l": np.array([5.0, 5.1])}, refine_range=0.1
    )
    data = codec.encode(lib)
    back = codec.decode(data, ElementLibrary)
    assert codec.encode(back) == data
    assert back.meshes[1].name == "b" and back.refine_range == 0.1
    assert np.array_equal(back.props["p"], lib.props["p"])


def test_dict_order_does_not_change_bytes():
    a = Table({"x": np.arange(3), "y": np.ones(3)})
    b = Table({"y": np.ones(3), "x": np.arange(3)})
    assert codec.encode(a) == codec.encode(b)


def test_floats_keep_every_bit_and_arrays_come_back_read_only():
    p = Placement(np.array([[0.1, 0.2, 0.3]]), np.array([[0.0, 0.0, 1.0]]), kind_names=("rice",))
    back = codec.decode(codec.encode(p))
    assert back.positions.tobytes() == p.positions.tobytes()
    with pytest.raises(ValueError):
        back.positions[0, 0] = 1.0


def test_object_arrays_and_garbage_are_refused():
    with pytest.raises(TypeError, match="no pickle"):
        codec.encode(Table({"x": np.array([object()], dtype=object)}))
    with pytest.raises(codec.DecodeError):
        codec.decode(b"not a zip")
    with pytest.raises(codec.DecodeError, match="expected Mesh"):
        codec.decode(codec.encode(Table({"x": np.arange(2)})), Mesh)


def test_a_table_read_back_from_the_cache_writes_the_same_csv(tmp_path):
    """The codec stores a dict's keys sorted, so a table decoded from the cache has its columns in name order; the
    CSV it writes must not depend on that order (the main job's measure.csv changed its header on a cached run)."""
    from nodegraph.output_files import write_output

    table = Table({"frame": np.arange(3), "skin": np.ones(3), "overlap": np.zeros(3)}, index="frame")
    (tmp_path / "cold").mkdir()
    (tmp_path / "cached").mkdir()
    cold = write_output(table, tmp_path / "cold", "t")[0].read_bytes()
    cached = write_output(codec.decode(codec.encode(table)), tmp_path / "cached", "t")[0].read_bytes()
    assert cold == cached
    assert cold.splitlines()[0] == b"frame,overlap,skin"
