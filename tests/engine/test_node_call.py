"""NodeSpec.call: one node run outside a recipe, with parameters validated and the context the executor gives."""

import numpy as np
import pytest

from nodegraph.errors import NodeDeclarationError
from nodegraph.node import In, Out, node
from nodegraph.params import Param, ParamValueError
from nodegraph.values import Mesh


def test_defaults_are_filled_and_values_validated(registry):
    points = registry["toy_points"]
    spheres = points.call()
    assert len(spheres) == 10  # count's default
    assert len(points.call(count="25")) == 25  # coerced as a recipe value is
    with pytest.raises(ParamValueError, match="out of range"):
        points.call(count=0)
    with pytest.raises(TypeError, match="no input or parameter \\['cuont'\\]"):
        points.call(cuont=5)


def test_seed_reaches_random_nodes_only(registry):
    points = registry["toy_points"]
    assert np.array_equal(points.call(seed=3).centers, points.call(seed=3).centers)
    assert not np.array_equal(points.call(seed=3).centers, points.call(seed=4).centers)
    shifted = registry["toy_shift"].call(spheres=points.call(), dx=1.5)
    assert np.allclose(shifted.centers[:, 0] - points.call().centers[:, 0], 1.5)


def test_inputs_missing_or_unwired(registry):
    with pytest.raises(TypeError, match="needs \\['spheres'\\]"):
        registry["toy_shift"].call(dx=1.0)
    merged = registry["toy_merge"].call(parts=[registry["toy_points"].call(count=2)] * 3)
    assert len(merged["spheres"]) == 6


def test_effects_are_those_asked_for_and_implemented(registry):
    physics = registry["toy_physics"]
    spheres = registry["toy_points"].call()
    assert not physics.call(spheres=spheres)["effects"].columns["gravity"][0]
    out = physics.call(spheres=spheres, effects=("gravity", "friction"))
    assert out["effects"].columns["gravity"][0] and out["effects"].columns["count"][0] == 2
    with pytest.raises(ValueError, match="does not implement the effects \\['contact'\\]"):
        physics.call(spheres=spheres, effects=("gravity", "contact"))


def test_check_between_parameters_applies():
    @node(
        "toy_range",
        outputs={"mesh": Out(Mesh)},
        params={"lo": Param(float, 0.0), "hi": Param(float, 1.0)},
        check=lambda p: [("hi", "must exceed lo")] if p["hi"] <= p["lo"] else [],
    )
    def toy_range(ctx, *, lo, hi):
        return Mesh(np.eye(3) * hi, [[0, 1, 2]])

    assert toy_range.call(hi=2.0).vertices.max() == 2.0
    with pytest.raises(ParamValueError, match="hi: must exceed lo"):
        toy_range.call(lo=3.0)


def test_seed_and_effects_cannot_name_a_port_or_parameter():
    for kind in ("inputs", "params"):
        declared = {"seed": In(Mesh)} if kind == "inputs" else {"effects": Param(int, 1)}
        with pytest.raises(NodeDeclarationError, match="cannot name an input or parameter"):
            node("bad", outputs={"y": Out(Mesh)}, **{kind: declared})(lambda ctx, **kw: None)
