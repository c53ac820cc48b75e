"""The shade node — SPEC §4: materials per kind/part, CDRF colours, water content, bad input."""

import hashlib

import numpy as np
import pytest

from nodegraph.context import Context
from nodegraph.params import ParamValueError
from nodes.shading import shade


def test_materials_per_kind_and_ikura_parts(shaded):
    names = [m.name for m in shaded.materials]
    assert names == ["rice", "ikura_membrane", "ikura_yolk", "ceramic"]
    membrane = shaded.materials[1]
    assert membrane.transmission > 0 and membrane.base_color[0] > membrane.base_color[2]
    assert len(shaded.meshes) == 16 + 3 * 2 + 1
    assert sum(m.name.endswith("/yolk") for m in shaded.meshes) == 3
    for mesh in shaded.meshes:
        assert mesh.colors.shape == (len(mesh.vertices), 3)
        assert mesh.colors.min() >= 0 and mesh.colors.max() <= 1
        assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1, atol=1e-6)


def test_wetter_rice_is_whiter_and_glows_past_the_terminator(scene_inputs):
    light = {"light_directions": [(1.0, 0.0, 0.0)], "ambient": 0.0}
    dry = shade.call(**scene_inputs, water_content=0.0, **light)
    wet = shade.call(**scene_inputs, water_content=24.0, **light)
    grain_dry, grain_wet = dry.meshes[0], wet.meshes[0]
    shadow = grain_dry.normals[:, 0] < -0.1  # facing away from the light: Lambert gives 0
    assert shadow.any()
    assert grain_wet.colors[shadow].mean() > grain_dry.colors[shadow].mean() + 0.005
    assert wet.materials[0].base_color[2] > dry.materials[0].base_color[2]


def test_same_input_gives_bit_identical_colours(scene_inputs):
    def digest():
        scene = shade.call(**scene_inputs)
        h = hashlib.sha256()
        for mesh in scene.meshes:
            h.update(np.ascontiguousarray(mesh.colors).tobytes())
            h.update(np.ascontiguousarray(mesh.vertices).tobytes())
        return h.hexdigest()

    assert digest() == digest()


def test_ice_with_syrup_on_top(scene_inputs):
    from dataclasses import replace

    rice, _ = scene_inputs["aggregates"]
    heights = rice.placement.positions + np.c_[np.zeros((len(rice.placement), 2)), np.arange(len(rice.placement))]
    ice = replace(
        rice, placement=replace(rice.placement, positions=heights), libraries=(replace(rice.libraries[0], kind="ice"),)
    )
    scene = shade.call(aggregates=[ice], syrup_coverage=0.5)
    assert {m.name for m in scene.materials} == {"ice", "ice_syrup"}
    assert all(m.ior == pytest.approx(1.31) and m.transmission > 0 for m in scene.materials)
    syrup = [
        mesh.vertices[:, 2].mean()
        for mesh, k in zip(scene.meshes, scene.material_of)
        if scene.materials[k].name == "ice_syrup"
    ]
    plain = [
        mesh.vertices[:, 2].mean()
        for mesh, k in zip(scene.meshes, scene.material_of)
        if scene.materials[k].name == "ice"
    ]
    assert min(syrup) > max(plain)  # syrup soaks the top of the mound


@pytest.mark.parametrize(
    "name, value",
    [
        ("water_content", 30.0),
        ("syrup_color", (1.2, 0.0, 0.0)),
        ("scenery_color", (-0.1, 0.2, 0.2)),
        ("light_colors", [(0.5, 2.0, 0.5)]),
    ],
)
def test_out_of_range_parameters_are_refused_before_running(name, value):
    with pytest.raises(ParamValueError):
        shade.params[name].validate(value)


def test_bad_input_at_run_time_gives_clear_errors(scene_inputs):
    with pytest.raises(ValueError, match="intensity > 0"):
        shade.call(**scene_inputs, light_intensities=[0.0])
    with pytest.raises(ValueError, match="zero vector"):
        shade.call(**scene_inputs, light_directions=[(0.0, 0.0, 0.0)])
    # Past the declaration (as a caller skipping validation would): the node's own checks still refuse.
    unchecked = {**shade.resolve_params({}), **scene_inputs}
    with pytest.raises(ValueError, match="linear RGB"):
        shade(Context.standalone(), **{**unchecked, "syrup_color": (1.5, 0.0, 0.0)})
    with pytest.raises(ValueError, match="water_content"):
        shade(Context.standalone(), **{**unchecked, "water_content": 25.0})
    with pytest.raises(ValueError, match="presets"):
        shade.call(**scene_inputs, presets=["japonica=marble"])
    assert shade.check(
        {"light_directions": [(0, 0, 1)] * 2, "light_colors": [(1, 1, 1)] * 3, "light_intensities": [1.0]}
    )


def test_unknown_kind_and_empty_aggregates_are_refused(scene_inputs):
    from dataclasses import replace

    rice, _ = scene_inputs["aggregates"]
    pebbles = replace(rice, libraries=(replace(rice.libraries[0], kind="pebble"),))
    with pytest.raises(ValueError, match="pebble"):
        shade.call(aggregates=[pebbles])
    assert shade.call(aggregates=[pebbles], presets=["pebble=rice"]).materials[0].name == "rice"
    empty = replace(rice, placement=rice.placement.subset(np.zeros(len(rice.placement), bool)))
    with pytest.raises(ValueError, match="no elements"):
        shade.call(aggregates=[empty])


def test_scene_carries_the_cdrf_sigma_per_vertex(scene_inputs):
    """σ = σ₀|κ| per vertex for renderers (the preview's translucency); wetter rice, wider kernels."""
    dry = shade.call(**scene_inputs, water_content=0.0)
    wet = shade.call(**scene_inputs, water_content=24.0)
    assert [len(s) for s in wet.cdrf_sigma] == [len(m.vertices) for m in wet.meshes]
    assert wet.cdrf_sigma[0].mean() > dry.cdrf_sigma[0].mean() > 0
    rice_wet, rice_dry = wet.materials[0], dry.materials[0]
    assert rice_wet.sheen > rice_dry.sheen and rice_wet.clearcoat > rice_dry.clearcoat
    assert rice_wet.roughness < rice_dry.roughness  # the water film glosses
