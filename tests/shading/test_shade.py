"""The shade node — SPEC §4: materials per kind/part, CDRF colours, water content, bad input."""

import hashlib

import numpy as np
import pytest

from nodegraph.context import Context
from nodegraph.params import ParamValueError
from nodes.material import cooked_rice
from nodes.material.cooked import cooked_material
from nodes.shading import shade
from nodes.shading.materials import is_ice


def test_materials_per_kind_and_ikura_parts(shaded):
    names = [m.name for m in shaded.materials]
    assert names[0] == "rice" and names[-1] == "ceramic" and "ikura_yolk" in names
    membranes = [m for m in shaded.materials if m.name.startswith("ikura_membrane_")]
    assert len(membranes) == 3  # three eggs, each its own tint
    assert all(m.transmission > 0 and m.base_color[0] > m.base_color[2] for m in membranes)
    assert not any("eye" in m.name for m in shaded.materials)  # the eye is the membrane's own colour, no piece
    assert len(shaded.meshes) == 16 + 3 * 2 + 1  # each egg: its membrane, one closed mesh, and its yolk
    assert sum(m.name.endswith("/yolk") for m in shaded.meshes) == 3
    for k, mesh in enumerate(shaded.meshes):  # only the membranes carry their own transmittance
        own = shaded.vertex_transmittance(k)
        assert (own is not None) == mesh.name.endswith("/membrane")
        if own is not None:
            assert own.shape == (len(mesh.vertices), 3) and own.max() <= 1
            edges = np.sort(mesh.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
            assert (np.unique(edges, axis=0, return_counts=True)[1] == 2).all()  # closed: every edge two faces
    for mesh in shaded.meshes:
        assert mesh.colors.shape == (len(mesh.vertices), 3)
        assert mesh.colors.min() >= 0 and mesh.colors.max() <= 1
        assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1, atol=1e-6)


def test_wetter_rice_is_whiter_and_glows_past_the_terminator(scene_inputs):
    light = {"light_directions": [(1.0, 0.0, 0.0)], "baked_ambient": 0.0}
    dry = shade.call(**scene_inputs, material=cooked_material(water_content=0.0), **light)
    wet = shade.call(**scene_inputs, material=cooked_material(water_content=24.0), **light)
    grain_dry, grain_wet = dry.meshes[0], wet.meshes[0]
    shadow = grain_dry.normals[:, 0] < -0.1  # facing away from the light: Lambert gives 0
    assert shadow.any()
    assert grain_wet.colors[shadow].mean() > grain_dry.colors[shadow].mean() + 0.005
    assert wet.materials[0].base_color[2] > dry.materials[0].base_color[2]


def test_same_input_gives_bit_identical_colours(scene_inputs):
    def digest():
        scene = shade.call(**scene_inputs, material=cooked_material())
        h = hashlib.sha256()
        for mesh in scene.meshes:
            h.update(np.ascontiguousarray(mesh.colors).tobytes())
            h.update(np.ascontiguousarray(mesh.vertices).tobytes())
        return h.hexdigest()

    assert digest() == digest()


def _ice_columns(scene_inputs, heights: dict[float, int]):
    """Ice columns: at each x (key), a stack of that many capsule 'flakes' 3 mm apart from z = 0 up."""
    from dataclasses import replace

    from nodes.values import Placement

    rice, _ = scene_inputs["aggregates"]
    positions = np.array([(x, 0.0, 3.0 * k) for x, n in heights.items() for k in range(n)])
    placement = Placement(positions, np.tile([0, 0, 1.0], (len(positions), 1)), kind_names=("ice",))
    return replace(rice, placement=placement, libraries=(replace(rice.libraries[0], kind="ice"),))


def _grade(scene, name_prefix="ice"):
    """Syrup share per element in scene order (0 plain ice … 100 soaked), from the material names."""
    names = [scene.materials[k].name for k in scene.material_of]
    return np.array([0 if n == "ice" else int(n.rsplit("_", 1)[1]) for n in names if n.startswith(name_prefix)])


def test_syrup_is_graded_by_depth_below_the_local_top_surface(scene_inputs):
    """A tall column (10 flakes) and a short one (3) side by side: syrup falls with the depth below each
    column's own top, so the short column's top flake is soaked although it sits lower than the tall
    column's half-soaked ones (a share of the mound's absolute height would leave it dry)."""
    ice = _ice_columns(scene_inputs, {0.0: 10, 20.0: 3})
    scene = shade.call(aggregates=[ice], syrup_depth=15.0, syrup_spread=0.0, syrup_levels=5)
    assert all(is_ice(m) for m in scene.materials)
    grade = _grade(scene)
    tall, short = grade[:10], grade[10:]
    assert tall[-1] == 100 and short[-1] == 100  # each column's top is soaked
    assert (np.diff(tall) >= 0).all() and tall[0] == 0 and len(set(tall)) >= 4  # graded down the column
    assert short[-1] > tall[2]  # the same height in the tall column is deeper below its top
    tints = {m.name: m.subsurface_color for m in scene.materials}
    assert tints["ice_syrup_100"][1] < tints["ice_syrup_40"][1] < tints["ice"][1]  # deeper red with more syrup
    poured = _grade(shade.call(aggregates=[ice], syrup_depth=15.0, syrup_spread=25.0, syrup_levels=5))
    assert poured[9] == 100 and poured[-1] < 60  # run sideways from the summit: the low column is a flank
    dry = shade.call(aggregates=[ice], syrup_depth=0.0)
    assert {m.name for m in dry.materials} == {"ice"}


def test_shaved_ice_is_white_and_its_syrup_colour_fades_downward(scene_inputs):
    """Kakigori (issue 26): plain ice is a white tuft of fine shavings (a scattering medium with no skin; where a
    renderer has no medium, a matte thin diffuser with an effective index near air's, no glassy facet) and the
    syrup's red is strongest on top and fades down the mound: down a column of flakes the red share of each flake's
    colour never rises, and half-soaked ice is already red (the dye absorbs: colour mixes geometrically with the
    concentration, not linearly to a pale pink)."""
    from nodes.export.look import boundary_roughness, has_skin, is_volumetric

    ice = _ice_columns(scene_inputs, {0.0: 10})
    scene = shade.call(aggregates=[ice], syrup_depth=27.0, syrup_spread=0.0, syrup_levels=6)
    plain = next(m for m in scene.materials if m.name == "ice")
    assert is_volumetric(plain) and not has_skin(plain) and max(plain.subsurface_radius) <= 0.3
    assert plain.transmission == 0 and plain.roughness >= 0.9 and plain.ior <= 1.15
    assert 0.2 <= plain.subsurface <= 0.5  # passes part of the diffuse light on to the flakes behind
    assert min(plain.base_color) >= 0.95 and min(plain.subsurface_color) >= 0.95  # white, not tinted
    colours = np.array([scene.materials[k].subsurface_color for k in scene.material_of])  # bottom flake first
    redness = colours[:, 0] / colours.sum(axis=1)
    assert (np.diff(redness) >= 0).all() and redness[-1] > 0.6 and redness[0] < 0.34  # red on top, white below
    half = next(m for m in scene.materials if m.name == "ice_syrup_50")
    assert half.subsurface_color[1] < 0.4  # linear mixing gives 0.55: pink
    # soaked through, the syrup joins up between the shavings: one wet, glossy surface; damp ice keeps its pores open
    grades = sorted((m for m in scene.materials if m.name.startswith("ice_syrup_")), key=lambda m: m.clearcoat)
    assert not has_skin(grades[0]) and has_skin(grades[-1]) and has_skin(half)
    assert boundary_roughness(grades[-1]) <= 0.1


def _ice_ring(scene_inputs, columns=24, radius=12.0, height=8):
    """A ring of ``columns`` equal ice columns (``height`` flakes 3 mm apart) around the z axis."""
    from dataclasses import replace

    from nodes.values import Placement

    rice, _ = scene_inputs["aggregates"]
    angles = 2 * np.pi * np.arange(columns) / columns
    positions = np.array([(radius * np.cos(a), radius * np.sin(a), 3.0 * k) for a in angles for k in range(height)])
    placement = Placement(positions, np.tile([0, 0, 1.0], (len(positions), 1)), kind_names=("ice",))
    return replace(rice, placement=placement, libraries=(replace(rice.libraries[0], kind="ice"),))


def test_syrup_runs_down_in_streaks_and_soaked_ice_is_bright_translucent_red(scene_inputs):
    """Kakigori (issue 26, the soaked top): syrup runs down the flanks in streaks, not as an even band: around a
    ring of equal columns some soak deeper than others, the same for the same seed; the soaked ice is the syrup's
    bright red (a dye that absorbs green and blue, not a dusky pigment) and passes most of its light on."""
    ring = _ice_ring(scene_inputs)
    soak = {"syrup_depth": 9.0, "syrup_spread": 0.0, "syrup_levels": 8}
    even = _grade(shade.call(aggregates=[ring], **soak)).reshape(24, 8)
    assert (even == even[0]).all()  # no runs: every column alike
    runs = {"syrup_runs": 6, "syrup_run_length": 12.0}
    streaked = shade.call(aggregates=[ring], seed=3, **soak, **runs)
    columns = _grade(streaked).reshape(24, 8)
    soaked_flakes = (columns > 0).sum(axis=1)
    assert soaked_flakes.max() >= soaked_flakes.min() + 2 and (columns >= even).all()  # some run further down
    again = shade.call(aggregates=[ring], seed=3, **soak, **runs)
    assert (_grade(again) == _grade(streaked)).all()  # drawn from the seed
    assert not (_grade(shade.call(aggregates=[ring], seed=4, **soak, **runs)) == _grade(streaked)).all()

    full = next(m for m in streaked.materials if m.name == "ice_syrup_100")
    assert full.base_color[0] >= 0.9 and max(full.base_color[1:]) <= 0.1  # bright, saturated red
    assert full.subsurface >= 0.8  # passes most of its light on: translucent, not an opaque leaf


def test_chestnut_is_its_own_golden_waxy_material(scene_inputs):
    from dataclasses import replace

    rice, _ = scene_inputs["aggregates"]
    half = np.arange(len(rice.placement)) % 2
    mixed = replace(
        rice,
        placement=replace(rice.placement, kinds=half, kind_names=("japonica", "chestnut")),
        libraries=(rice.libraries[0], replace(rice.libraries[0], kind="chestnut")),
    )
    scene = shade.call(aggregates=[mixed], material=cooked_material(water_content=18.0))
    materials = {m.name: m for m in scene.materials}
    assert set(materials) == {"rice", "chestnut"}
    kuri, grain = materials["chestnut"], materials["rice"]
    r, g, b = kuri.base_color
    # gardenia gold, Munsell 4Y 8/8 taken paler: a pale cream (g < 3·b) read as "pale mustard blobs" (issue 48)
    assert r > g > 3 * b > 0.3
    assert kuri.roughness > grain.roughness and kuri.subsurface < grain.subsurface  # satin, dense: nearly opaque
    assert 0.3 < kuri.clearcoat and kuri.clearcoat_roughness > grain.clearcoat_roughness  # a soft, moist glint


@pytest.mark.parametrize("kind", ["salmon", "tuna"])
def test_fish_topping_parts_get_flesh_and_fat(scene_inputs, kind):
    from dataclasses import replace

    from nodegraph.values import Mesh

    rice, _ = scene_inputs["aggregates"]
    grain = rice.libraries[0].meshes[0]
    parts = (grain.vertices[grain.faces].mean(axis=1)[:, 0] > 0).astype(np.int32)  # half the faces are fat
    slab = Mesh(grain.vertices, grain.faces, parts=parts, name=kind)
    library = replace(rice.libraries[0], kind=kind, meshes=(slab,))
    fish = replace(rice, placement=rice.placement.subset([0]), libraries=(library,))
    scene = shade.call(aggregates=[fish])
    assert [m.name for m in scene.meshes] == [f"{kind}/0000/flesh", f"{kind}/0000/fat"]
    flesh, fat = (scene.materials[k] for k in scene.material_of)
    assert flesh.name == f"{kind}_flesh" and fat.name == f"{kind}_fat"
    from nodes.export.look import boundary_roughness, is_volumetric

    # light under the flesh's skin (a medium in the preview), the fat an opaque paler line; both under a wet film
    assert is_volumetric(flesh) and not is_volumetric(fat) and np.mean(fat.base_color) > np.mean(flesh.base_color)
    assert boundary_roughness(flesh) <= 0.15 and fat.clearcoat > 0 and fat.clearcoat_roughness <= 0.15
    bad = replace(fish, libraries=(replace(fish.libraries[0], meshes=(replace(slab, parts=parts * 2),)),))
    with pytest.raises(ValueError, match="flesh"):
        shade.call(aggregates=[bad])


def test_water_content_is_the_cooked_materials():
    """Shade has no water content of its own: the cooked material's (a recipe cannot state it twice)."""
    assert "water_content" not in shade.params and "material" in shade.inputs
    with pytest.raises(TypeError, match="moved to parameter 'water_content' of the cooked_rice node"):
        shade.call(aggregates=[], water_content=22.0)
    with pytest.raises(ParamValueError):
        cooked_rice.params["water_content"].validate(30.0)


def test_rice_without_a_cooked_material_is_refused(scene_inputs):
    with pytest.raises(ValueError, match="wire a cooked_rice node into input 'material'"):
        shade.call(**scene_inputs)


@pytest.mark.parametrize(
    "name, value",
    [
        ("syrup_color", (1.2, 0.0, 0.0)),
        ("scenery_color", (-0.1, 0.2, 0.2)),
        ("light_colors", [(0.5, 2.0, 0.5)]),
    ],
)
def test_out_of_range_parameters_are_refused_before_running(name, value):
    with pytest.raises(ParamValueError):
        shade.params[name].validate(value)


def test_bad_input_at_run_time_gives_clear_errors(scene_inputs):
    with pytest.raises(ValueError, match="zero vector"):
        shade.call(**scene_inputs, light_directions=[(0.0, 0.0, 0.0)])
    # Past the declaration (as a caller skipping validation would): the node's own checks still refuse.
    unchecked = {**shade.resolve_params({}), **scene_inputs}
    with pytest.raises(ValueError, match="linear RGB"):
        shade(Context.standalone(), **{**unchecked, "syrup_color": (1.5, 0.0, 0.0)})
    with pytest.raises(ValueError, match="intensity > 0"):
        shade(Context.standalone(), **{**unchecked, "light_intensities": [0.0]})
    with pytest.raises(ValueError, match="water_content"):
        cooked_material(water_content=25.0)
    with pytest.raises(ValueError, match="presets"):
        shade.call(**scene_inputs, presets=["japonica=marble"])
    assert shade.check(
        {"light_directions": [(0, 0, 1)] * 2, "light_colors": [(1, 1, 1)] * 3, "light_intensities": [1.0]}
    )


def test_a_dark_light_is_refused_by_its_declaration():
    """A new user's ``--set "shade.light_intensities=[0]"`` passed ``check`` (its range was 0–100) and failed in
    the shade node after 20 s of simulation."""
    with pytest.raises(ParamValueError) as refused:
        shade.params["light_intensities"].validate([0.0])
    assert "0.01 ≤ value" in refused.value.allowed
    assert shade.params["light_intensities"].validate([0.5]) == [0.5]


def test_a_misspelt_preset_is_refused_by_check_and_a_misspelt_kind_by_the_run(scene_inputs):
    """A new user's ``--set "shade.presets=[slamon=tuna]"`` changed nothing, without a word, and ``[salmon=tunaa]``
    passed ``check`` and failed after the simulation: a preset is checked with the recipe, a kind against the
    scene's kinds."""
    base = {"light_directions": [(0, 0, 1)], "light_colors": [(1, 1, 1)], "light_intensities": [1.0]}
    assert [name for name, _ in shade.check({**base, "presets": ["salmon=tunaa"]})] == ["presets"]
    assert not shade.check({**base, "presets": ["salmon=tuna"]})
    with pytest.raises(ValueError, match="'slamon' names no element kind of this scene; its kinds are "):
        shade.call(**scene_inputs, presets=["slamon=tuna"])


def test_unknown_kind_and_empty_aggregates_are_refused(scene_inputs):
    from dataclasses import replace

    rice, _ = scene_inputs["aggregates"]
    pebbles = replace(rice, libraries=(replace(rice.libraries[0], kind="pebble"),))
    with pytest.raises(ValueError, match="pebble"):
        shade.call(aggregates=[pebbles])
    scene = shade.call(aggregates=[pebbles], presets=["pebble=rice"], material=cooked_material())
    assert scene.materials[0].name == "rice"
    empty = replace(rice, placement=rice.placement.subset(np.zeros(len(rice.placement), bool)))
    with pytest.raises(ValueError, match="no elements"):
        shade.call(aggregates=[empty])


def test_scene_carries_the_cdrf_sigma_per_vertex(scene_inputs):
    """σ = σ₀|κ| per vertex for renderers (the preview's translucency); wetter rice, wider kernels."""
    dry = shade.call(**scene_inputs, material=cooked_material(water_content=0.0))
    wet = shade.call(**scene_inputs, material=cooked_material(water_content=24.0))
    assert [len(s) for s in wet.cdrf_sigma] == [len(m.vertices) for m in wet.meshes]
    assert wet.cdrf_sigma[0].mean() > dry.cdrf_sigma[0].mean() > 0
    rice_wet, rice_dry = wet.materials[0], dry.materials[0]
    assert rice_wet.sheen > rice_dry.sheen and rice_wet.clearcoat > rice_dry.clearcoat
    assert rice_wet.roughness < rice_dry.roughness  # the water film glosses


def test_cooked_rices_skin_is_a_medium_gloss_not_a_mirror():
    """The grain's skin (its starch-and-water film, the preview's film and the files' clear coat) is a wet gloss
    at the recipes' 15 %: at α 0.024 (roughness 0.156) each grain mirrored the key and read as a glossy pill, at
    α 0.11 (0.325) the sheen spread over the grain and art directors read it as dry, chalky rice; the wetter grain
    is the glossier, a dry one matte (docs/look.md, "A bowl of rice")."""
    from nodes.export.look import boundary_roughness
    from nodes.shading.materials import rice_material

    dry, cooked, wet = (boundary_roughness(rice_material(w)) for w in (0.0, 15.0, 24.0))
    assert 0.18 <= cooked <= 0.3  # α 0.032–0.09 at 15 %: neither a mirror nor chalk
    assert wet < cooked < dry  # no film on a dry grain: its own matte surface


def test_egg_tints_span_orange_to_red_orange_and_touching_eggs_differ():
    """The palette runs from orange to red-orange in CIELAB hue, lighter to deeper; eggs in a tight cluster draw
    tints seeded, no two neighbours alike, the same for the same seed."""
    from nodes.shading.materials import ikura_tints
    from nodes.shading.scene_shading import egg_tints

    def hue(rgb):  # CIELAB hue angle of a linear sRGB colour (D65)
        xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ rgb
        f = np.cbrt(xyz / np.array([0.9505, 1.0, 1.089]))
        return np.degrees(np.arctan2(200 * (f[1] - f[2]), 500 * (f[0] - f[1])))

    hues = [hue(np.array(m.subsurface_color)) for m in ikura_tints(12)]
    assert min(hues) < 45 and max(hues) > 58 and len({round(h, 3) for h in hues}) == 12
    grid = np.stack(np.meshgrid(*[np.arange(4) * 6.5] * 3), axis=-1).reshape(-1, 3)  # 64 touching eggs
    tints = egg_tints(grid, 12, seed=3)
    assert np.array_equal(tints, egg_tints(grid, 12, seed=3)) and not np.array_equal(tints, egg_tints(grid, 12, 4))
    touching = np.linalg.norm(grid[:, None] - grid[None], axis=-1) < 6.6
    np.fill_diagonal(touching, False)
    assert not (touching & (tints[:, None] == tints[None])).any()
    assert (egg_tints(grid, 1, seed=3) == 0).all()


def test_the_eye_is_the_droplet_seen_through_the_thinning_fluid_over_it():
    """Each membrane vertex keeps the egg's colour to the power of the fluid's depth under it (its distance to the
    oil droplet) over that depth with the droplet at the centre: palest at the eye's centre, fading with no edge to
    the egg's own colour on the far side; a concentric droplet leaves the egg its colour everywhere."""
    from nodes.elements import base_mesh
    from nodes.shading.scene_shading import _parts, eye_transmittance

    color = np.array([0.85, 0.10, 0.012])
    mesh = base_mesh.call(shape="ikura", diameter=6.5, subdivisions=3, eye_gap=0.15)
    (_, skin, _), (_, yolk, _) = _parts(mesh, ("membrane", "yolk"), "", "")
    skin, yolk = mesh.vertices[skin], mesh.vertices[yolk]
    own = eye_transmittance(skin, yolk, color)
    top, bottom = np.argmax(skin[:, 2]), np.argmin(skin[:, 2])
    r_o = np.linalg.norm(yolk - yolk.mean(axis=0), axis=1).mean()
    share = np.log(own[top, 1]) / np.log(color[1])  # the fluid over the eye's centre: eye_gap / (R − r_o)
    assert share == pytest.approx(0.15 / (3.25 - r_o), rel=0.05)
    assert own[bottom] == pytest.approx(color)  # the far side: the egg's colour
    angle = np.degrees(np.arccos(np.clip(skin[:, 2] / np.linalg.norm(skin, axis=1), -1, 1)))
    green = own[:, 1]
    for low, high in ((0, 20), (20, 40), (40, 60), (60, 90)):  # paler the nearer the eye's axis, no step
        assert green[(angle >= high) & (angle < high + 20)].mean() < green[(angle >= low) & (angle < high)].mean()
    concentric = base_mesh.call(shape="ikura", diameter=6.5, subdivisions=3, eye_gap=0.0)
    (_, skin, _), (_, yolk, _) = _parts(concentric, ("membrane", "yolk"), "", "")
    assert eye_transmittance(concentric.vertices[skin], concentric.vertices[yolk], color) == pytest.approx(
        np.tile(color, (len(skin), 1)), rel=0.02
    )


def test_the_oil_droplet_floats_to_the_top_of_a_turned_egg():
    """Issue 48: the eye pointed wherever the placement turned the egg (half into the rice). The droplet moves,
    unturned, straight above the egg's centre at its own distance, inside the skin; where the top is dented the
    lift shrinks until it fits."""
    from nodes.elements import base_mesh
    from nodes.shading.scene_shading import DROPLET_CLEARANCE, _parts, floated_droplet

    mesh = base_mesh.call(shape="ikura", diameter=7.0, subdivisions=2, eye_gap=0.15)
    (_, skin, _), (_, yolk, _) = _parts(mesh, ("membrane", "yolk"), "", "")
    turn = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])  # upside down: the eye at the bottom
    skin, yolk = mesh.vertices[skin] @ turn.T + 10.0, mesh.vertices[yolk] @ turn.T + 10.0
    lift = np.linalg.norm(yolk.mean(axis=0) - skin.mean(axis=0))
    up = floated_droplet(skin, yolk)
    assert up.mean(axis=0) - skin.mean(axis=0) == pytest.approx([0.0, 0.0, lift], abs=1e-6)
    assert np.ptp(up - yolk, axis=0) == pytest.approx(np.zeros(3), abs=1e-9)  # moved, not turned
    dented = skin.copy()
    top = dented[:, 2] > skin.mean(axis=0)[2] + 2.5
    dented[top, 2] = skin.mean(axis=0)[2] + 2.5  # a neighbour pressed the top flat
    fitted = floated_droplet(dented, yolk)
    height = fitted.mean(axis=0)[2] - skin.mean(axis=0)[2]
    assert 0.0 < height < lift
    assert fitted[:, 2].max() <= skin.mean(axis=0)[2] + 2.5 - DROPLET_CLEARANCE + 1e-6


def test_the_rice_filling_is_rice_and_the_glaze_has_no_satin_sheen(scene_inputs):
    """The rice under the top layer shows in the cooked rice's material (the gaps showed the bowl's dark floor);
    the bowl's glaze reflects only at its coat (a satin specular lobe of its own made it read grey and metallic)."""
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade

    bowl = scene_inputs["scenery"][0]
    material = cooked_material()
    filled = shade.call(**scene_inputs, material=material, filling=[bowl])
    rice = [filled.materials[m] for k, m in enumerate(filled.material_of) if filled.meshes[k].name == "rice_fill_0"]
    assert len(rice) == 1 and rice[0] is material.optics
    glaze = [m for m in filled.materials if m.name == "ceramic"][0]
    assert glaze.metallic == 0.0 and glaze.specular == 0.0 and glaze.clearcoat == 1.0
    from nodes.export.mitsuba_scene import material_bsdf

    glazed = material_bsdf(glaze, False)  # one clear coat over a diffuse body, no second (satin) lobe
    assert glazed["type"] in ("plastic", "roughplastic") and "specular" not in glazed and "sheen" not in glazed
    with pytest.raises(ValueError, match="filling"):  # eggs alone, no cooked rice wired
        shade.call(aggregates=scene_inputs["aggregates"][1:], scenery=[bowl], filling=[bowl])


def test_a_satin_glaze_spreads_the_studios_reflection(scene_inputs):
    """``scenery_roughness`` reaches the glaze: the preview's coat and the exported material take it, so a satin plate
    shows a soft sheen where a glossy one mirrors the softboxes."""
    from nodes.export.mitsuba_scene import material_bsdf
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade

    cooked = cooked_material()
    glazes = [
        next(
            m for m in shade.call(**scene_inputs, material=cooked, scenery_roughness=r).materials if m.name == "ceramic"
        )
        for r in (0.04, 0.3)
    ]
    assert [g.clearcoat_roughness for g in glazes] == [0.04, 0.3]
    glossy, satin = (material_bsdf(g, False)["alpha"] for g in glazes)
    assert satin > 10 * glossy
