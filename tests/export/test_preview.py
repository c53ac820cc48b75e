"""The preview node — Mitsuba 3 (scalar_rgb) path tracing of the materials, denoised by OIDN: what shows, the
material mapping, and bit-for-bit reproducibility."""

import dataclasses

import numpy as np
import pytest

from nodes.export import image_grid, preview


def _render(scene, **over):
    return preview.call(scene=scene, **{"width": 64, "height": 48, "samples": 2, **over}).pixels


def test_preview_shows_the_shaded_scene(shaded):
    image = _render(shaded)
    assert image.shape == (48, 64, 3) and image.dtype == np.uint8
    background = np.median(image[0], axis=0).astype(int)  # the top row is table: its typical colour
    differs = np.abs(image.astype(int) - background).sum(axis=2) > 30
    assert 0.1 < differs.mean() < 0.95  # the scene fills part of the frame, not all of it
    orange = (image[..., 0].astype(int) - image[..., 2].astype(int)) > 80
    assert orange.any()  # the ikura shows


def test_same_scene_and_seed_give_identical_png_bytes(shaded, tmp_path):
    from nodegraph.output_files import write_output

    def png(folder):
        write_output(preview.call(scene=shaded, width=64, height=48, samples=2), tmp_path / folder, "preview")
        return (tmp_path / folder / "preview.png").read_bytes()

    assert png("a") == png("b")


def test_renders_in_one_process_agree(shaded):
    """A watch session renders many previews in one process and caches them: every render of the same scene must
    give the same bits. With Mitsuba's scene optimisation on (``load_dict(optimize=True)`` merges identical
    objects), about one render in six of this scene came out different."""
    first = _render(shaded, width=32, height=24, samples=1, denoise=False)
    for _ in range(23):
        assert np.array_equal(_render(shaded, width=32, height=24, samples=1, denoise=False), first)


def test_denoising_removes_noise(shaded):
    noisy = _render(shaded, samples=1, denoise=False).astype(float)
    clean = _render(shaded, samples=1).astype(float)
    reference = _render(shaded, samples=32).astype(float)
    assert np.abs(clean - reference).mean() < np.abs(noisy - reference).mean()


def test_the_yolk_shows_through_the_membrane(shaded):
    """Remove the yolks: the eggs' pixels change (an opaque membrane would hide them)."""
    keep = [k for k, m in enumerate(shaded.meshes) if not m.name.endswith("/yolk")]
    hollow = dataclasses.replace(
        shaded,
        meshes=tuple(shaded.meshes[k] for k in keep),
        material_of=shaded.material_of[keep],
        cdrf_sigma=tuple(shaded.cdrf_sigma[k] for k in keep),
        transmittance=tuple(shaded.transmittance[k] for k in keep),
    )
    with_yolk, without = _render(shaded, samples=8).astype(int), _render(hollow, samples=8).astype(int)
    orange = (with_yolk[..., 0] - with_yolk[..., 2]) > 80
    assert np.abs(with_yolk - without)[orange].mean() > 5


def test_the_pale_droplet_shows_as_an_eye(shaded):
    """Each egg's oil droplet is a cloudy, pale honey-gold medium (``materials.DROPLET_COLOR``): light entering over
    the eye comes back out of it pale, so the eggs' pixels are more golden than with a droplet of the fluid's own
    orange (the droplet before: (1.0, 0.50, 0.10), free path up to 1 mm), where the eye did not show."""
    from nodes.shading import materials as mat

    yolk = mat.ikura_materials()[1]
    orange = dataclasses.replace(yolk, subsurface_color=(1.0, 0.50, 0.10), subsurface_radius=(1.0, 0.4, 0.1))
    index = next(k for k, m in enumerate(shaded.materials) if m.name == yolk.name)
    materials = tuple(orange if k == index else m for k, m in enumerate(shaded.materials))
    pale = _render(shaded, width=96, height=72, samples=16).astype(float)
    before = _render(dataclasses.replace(shaded, materials=materials), width=96, height=72, samples=16).astype(float)
    eggs = (pale[..., 0] - pale[..., 2]) > 80

    def golden(image):  # green over red on the palest tenth of the eggs' pixels: their eyes
        return float(np.percentile((image[..., 1] / image[..., 0].clip(1))[eggs], 90))

    print(f"eggs' palest green / red: pale droplet {golden(pale):.3f}, orange droplet {golden(before):.3f}")
    assert golden(pale) > golden(before) + 0.03


def test_a_white_body_under_a_glaze_returns_all_the_light_of_a_white_furnace():
    """Energy conservation: a white body under a clear glaze (``materials.coated``) in a uniform white sky absorbs
    nothing, so it looks as bright as the sky. The glaze is a dielectric interface over the body (``coat_bsdf``:
    Mitsuba's plastic, GGX at the coat's IOR, F0 0.04 as Cycles' coat); Disney's coat in Mitsuba's principled adds
    its reflection on top of the body's, 1.13 of the sky (docs/look.md, "Noise or a different picture")."""
    from nodes.export.furnace import white_furnace
    from nodes.export.mitsuba_scene import material_bsdf
    from nodes.shading import materials as mat

    glaze = material_bsdf(mat.coated("white", (1, 1, 1), 0.04), False)
    assert abs(white_furnace(glaze) - 1.0) < 0.03


def test_material_mapping():
    from nodes.export.mitsuba_scene import diffuse_transmission, material_bsdf
    from nodes.shading import materials as mat

    membrane, yolk = mat.ikura_materials()
    assert material_bsdf(membrane, False)["type"] in ("dielectric", "roughdielectric")
    assert material_bsdf(membrane, False)["int_ior"] == pytest.approx(1.36)
    # a smooth wet chorion: a sharp highlight, the droplet seen sharply through it (at roughness 0.2, α 0.04, the
    # eggs read frosted); the preview's skin and the files' transmission roughness are the one value
    assert material_bsdf(membrane, False).get("alpha", 0.0) <= 0.01
    assert membrane.roughness == membrane.transmission_roughness
    ice, syrup = mat.ice_materials((0.75, 0.02, 0.06))
    plain = material_bsdf(ice, False)  # a tuft of shavings in air: a matte thin diffuser, not clear ice
    assert plain["type"] == "principledthin" and plain["eta"] == pytest.approx(1.1) and plain["roughness"] == 1.0
    soaked = material_bsdf(syrup, False)  # translucent all over: no opaque coated share (issue 26)
    assert soaked["type"] == "principledthin"
    assert soaked["base_color"]["value"][0] > 2 * soaked["base_color"]["value"][1]  # the syrup dyes the ice red
    assert soaked["diff_trans"] > plain["diff_trans"] and soaked["spec_trans"] > 0  # soaked: translucent
    # principledthin passes on diff_trans / 2 of its diffuse light: the ice's subsurface is that share
    assert plain["diff_trans"] == pytest.approx(2 * ice.subsurface) and soaked["diff_trans"] == pytest.approx(1.8)
    from nodes.export.gltf_writer import material_json

    gltf, _ = material_json(syrup, syrup.subsurface)  # the glTF carries both transmissions, as the preview renders
    assert gltf["extensions"]["KHR_materials_diffuse_transmission"]["diffuseTransmissionFactor"] == 0.9
    assert gltf["extensions"]["KHR_materials_transmission"]["transmissionFactor"] == syrup.transmission
    glaze = material_bsdf(mat.ceramic_material((0.05, 0.07, 0.16)), False)
    assert glaze["type"] in ("plastic", "roughplastic") and glaze["int_ior"] == pytest.approx(1.5)
    wet, dry = mat.rice_material(24.0), mat.rice_material(0.0)
    assert material_bsdf(dry, True)["type"] == "principledthin"
    assert material_bsdf(wet, True)["bsdf_1"]["clearcoat"] > 0  # the water film's coat
    assert material_bsdf(wet, True)["bsdf_0"]["diff_trans"]["name"] == "vertex_trans"
    sigma = np.linspace(0.0, 1.2, 7)  # grains at 0–24 % water: σ₀ ≈ 0.15–1.2 rad·mm, |κ| ≈ 1 /mm
    assert (np.diff(diffuse_transmission(wet, sigma)) > 0).all()  # more curved, more light through (CDRF)
    assert (diffuse_transmission(wet, sigma)[1:] > diffuse_transmission(dry, sigma)[1:]).all()


def test_zero_sun_direction_is_refused(shaded):
    with pytest.raises(ValueError, match="sun_direction"):
        _render(shaded, sun_direction=(0.0, 0.0, 0.0))


def test_image_grid_places_tiles_with_captions():
    from nodegraph.values import Image

    tiles = [Image(np.full((10, 12, 3), 40 * k, np.uint8)) for k in range(4)]
    grid = image_grid.call(images=tiles, columns=2, gap=2, labels=["a", "b", "c", "d"], label_height=8).pixels
    assert grid.shape == (2 * (10 + 8) + 3 * 2, 2 * 12 + 3 * 2, 3)
    assert (grid[2:12, 2 + 12 + 2 : 2 + 24 + 2] == 40).all()  # the second tile, right of the first
    with pytest.raises(ValueError, match="same size"):
        image_grid.call(images=[tiles[0], Image(np.zeros((5, 5, 3), np.uint8))])
    with pytest.raises(ValueError, match="labels"):
        image_grid.call(images=tiles, labels=["only one"])


def _ice_heap(count=400, radius=8.0, seed=0):
    """A heap of ``count`` plain ice flakes (4 × 3 × 0.4 mm, random orientations) in a half ball, shaded."""
    from scipy.spatial.transform import Rotation

    from nodegraph.values import Mesh
    from nodes.elements import grain_shapes
    from nodes.shading import shade
    from nodes.values import Aggregate, ElementLibrary, Placement

    rng = np.random.default_rng(seed)
    flake = Mesh(*grain_shapes.ice_flake(4.0, 3.0, 0.4, 0.3, 0))
    direction = rng.normal(size=(count, 3))
    direction[:, 2] = np.abs(direction[:, 2])
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    positions = direction * radius * rng.uniform(0, 1, (count, 1)) ** (1 / 3)
    rotations = Rotation.random(count, random_state=seed).as_matrix()
    placement = Placement(positions, np.tile([0, 0, 1.0], (count, 1)), rotations=rotations, kind_names=("ice",))
    return shade.call(aggregates=[Aggregate(placement, (ElementLibrary("ice", (flake,)),))], syrup_depth=0.0)


def test_shaved_ice_scatters_light_under_no_skin(tmp_path):
    """Shaved ice (issue 26) is white from countless fine interfaces, not a glassy crystal. With subsurface on,
    each flake is a scattering medium behind no boundary (``null``: a tuft of shavings whose pores open to the
    air), lit from inside too (a null boundary lets shadow rays out), with no glint in the key's highlight pass.
    Off, it is a matte thin diffuser (principledthin, one diffuse-transmission weight for the whole flake)."""
    import mitsuba as mi

    from nodes.export.mitsuba_scene import Camera, gloss, scene_dict
    from nodes.shading.materials import is_ice

    mi.set_variant("scalar_rgb")
    heap = _ice_heap(count=20)
    camera = Camera(30.0, 20.0, 35.0, 0.1)
    on = scene_dict(heap, tmp_path, camera, 32, 24, 1, (-0.45, -0.6, 0.75), subsurface=True)
    ice = [on[f"shape_{k}"] for k, m in enumerate(heap.materials) if is_ice(m)]
    assert ice and all(shape["bsdf"]["type"] == "null" for shape in ice)
    assert all(shape["interior"]["type"] == "homogeneous" and shape["interior"]["sample_emitters"] for shape in ice)
    assert on["integrator"]["type"] == "volpath"
    off = scene_dict(heap, tmp_path, camera, 32, 24, 1, (-0.45, -0.6, 0.75), subsurface=False)
    ice = [off[f"shape_{k}"] for k, m in enumerate(heap.materials) if is_ice(m)]
    assert ice and all("interior" not in shape for shape in ice)
    assert all(shape["bsdf"]["type"] == "principledthin" for shape in ice)
    assert all(isinstance(shape["bsdf"]["diff_trans"], float) for shape in ice)  # not the CDRF per vertex
    assert all(gloss(m)[0] == 0 for m in heap.materials if is_ice(m))


@pytest.mark.parametrize("subsurface", [True, False])
def test_a_heap_of_ice_flakes_is_bright_like_shaved_ice(subsurface):
    """Shaved ice is white: light scattered in its shavings comes back out. The ice heap's mean luminance, against the
    same heap in a white diffuse material (albedo 0.9) under the same light: with each flake a medium behind no skin
    (subsurface on) 1.22, the same medium behind a dielectric skin at the tuft's index (1.1, rough) 0.28: grey glass
    (``look.has_skin`` true for ice; seen failing); as a matte thin diffuser (subsurface off) 1.31; 0.44 as clear
    glassy plates, 0.075 with paths cut off after 10 bounces."""
    from nodes.export.mitsuba_scene import Camera, render_layers
    from nodes.shading.materials import is_ice
    from nodes.values import Material

    heap = _ice_heap()

    def luminance(material=None):
        materials = tuple(material if material and is_ice(m) else m for m in heap.materials)
        camera = Camera(30.0, 20.0, 35.0, 0.1)
        scene = dataclasses.replace(heap, materials=materials)
        layers = render_layers(scene, camera, 64, 48, 4, (-0.45, -0.6, 0.75), subsurface=subsurface)
        return layers.color @ np.array([0.2126, 0.7152, 0.0722])

    white = luminance(Material("white", base_color=(0.9, 0.9, 0.9), roughness=1.0))
    black = luminance(Material("black", base_color=(0.0, 0.0, 0.0), roughness=1.0))
    ice = luminance()
    flakes = white - black > 0.2  # pixels that show the heap
    assert flakes.mean() > 0.1
    assert ice[flakes].mean() / white[flakes].mean() > 0.9


def test_subsurface_puts_a_medium_inside_rice_and_yolks(shaded, tmp_path):
    """With subsurface on, the rice and yolk shapes carry a homogeneous medium and the integrator is volpath; the
    yolk's behind a dielectric skin, the rice's behind its film, which passes light unbent (``null``; its sheen is
    the film pass), so the rice's medium samples the lights; off, none does and the path tracer is the plain one."""
    from nodes.export.mitsuba_scene import Camera, scene_dict

    camera = Camera(40.0, 20.0, 35.0, 0.1)
    names = {f"shape_{k}": m.name for k, m in enumerate(shaded.materials)}
    on = scene_dict(shaded, tmp_path, camera, 64, 48, 2, (0, 0, 1), subsurface=True)
    with_media = {names[key] for key, shape in on.items() if isinstance(shape, dict) and "interior" in shape}
    assert with_media == {"rice", "ikura_yolk"} and on["integrator"]["type"] == "volpath"  # (ice: its own test)
    rice, yolk = (next(shape for key, shape in on.items() if names.get(key) == name) for name in ("rice", "ikura_yolk"))
    assert rice["bsdf"]["type"] == "null" and rice["interior"]["type"] == "homogeneous"
    assert rice["interior"]["sample_emitters"] is True
    # issue 27: no light sampling from inside a medium behind a dielectric skin: it blocks every such shadow ray
    assert yolk["bsdf"]["type"] in ("dielectric", "roughdielectric") and yolk["interior"]["sample_emitters"] is False
    off = scene_dict(shaded, tmp_path, camera, 64, 48, 2, (0, 0, 1), subsurface=False)
    assert not any(isinstance(shape, dict) and "interior" in shape for shape in off.values())
    assert off["integrator"]["type"] == "path"


def test_a_grains_skin_over_a_clear_medium_returns_all_the_light_of_a_white_furnace(shaded):
    """Energy conservation: a rice grain (its film over its medium, albedo raised to 1) in a uniform white sky
    absorbs nothing, so it looks exactly as bright as the sky, its medium sampling the sky through the film at every
    scattering event (1.0007 at 512 spp; 1.011 at 32). Mitsuba's rough dielectric at the film's roughness (α 0.11)
    returned 0.93, losing the microfacets' multiple scattering at every crossing (docs/look.md, "The skin over a
    medium conserves energy")."""
    from nodes.export import mitsuba_scene as ms
    from nodes.export.furnace import white_furnace

    rice = next(m for m in shaded.materials if m.name == "rice")
    clear = {**ms.medium(rice), "albedo": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}
    assert abs(white_furnace(ms.boundary_bsdf(rice), clear, spp=512) - 1.0) < 0.01


def test_a_grains_skin_glints_at_fresnels_full_share(shaded, tmp_path):
    """The dielectric skin over a rice grain's medium reflects the key's bright core (the glints' pass) at weight 1
    and the skin's roughness, as it reflects the rest of the studio in the path-traced pass and as Cycles'
    transmission lobe does; at the coat's weight (0.31 at 15 % water) the rice glinted a third as much. With
    subsurface off the grain is a thin surface and its gloss stays the coat's."""
    import mitsuba as mi

    from nodes.export import mitsuba_scene as ms
    from nodes.export.look import boundary_roughness

    mi.set_variant("scalar_rgb")
    camera = ms.Camera(40.0, 20.0, 35.0, 0.1)
    rice = next(k for k, m in enumerate(shaded.materials) if m.name == "rice")
    material = shaded.materials[rice]
    assert 0 < material.clearcoat < 1
    for subsurface, weight in ((True, 1.0), (False, material.clearcoat)):
        description = ms.scene_dict(shaded, tmp_path, camera, 32, 24, 1, (0, 0, 1), subsurface=subsurface)
        bsdf = ms.highlight_dict(shaded, description)[f"shape_{rice}"]["bsdf"]
        assert bsdf["specular_reflectance"]["value"] == pytest.approx([weight] * 3)
    assert ms.gloss(material, skin=True) == (1.0, boundary_roughness(material))


def test_wet_rice_scatters_whiter_and_farther():
    """The medium follows the water content (G fig. 3.1.2.1): wetter rice has a longer mean free path and a higher
    albedo; at 24 % its mean free path is potato's (Jensen et al. 2001: 1/σ′s = 1.43–1.82 mm; it was 1.24 mm, grains
    that read as opaque pebbles)."""
    from nodes.export.look import random_walk_coefficients
    from nodes.shading.materials import rice_material

    dry, wet = (rice_material(w) for w in (0.0, 24.0))
    (t_dry, a_dry), (t_wet, a_wet) = (
        random_walk_coefficients(m.subsurface_color, m.subsurface_radius) for m in (dry, wet)
    )
    assert (1 / t_wet > 1 / t_dry).all() and (a_wet > a_dry).all()
    assert 1.43 <= 1 / t_wet[0] <= 1.82 and a_wet.min() > 0.99
    # Chiang et al. 2016: a white surface (A → 1) needs albedo → 1 and σt = 1 / (d · 1.04)
    t, a = random_walk_coefficients((0.999, 0.999, 0.999), (1.0, 1.0, 1.0))
    assert a.min() > 0.998 and t[0] == pytest.approx(1 / (1.0 * (1.9 - 0.999 + 3.5 * 0.199**2)))


@pytest.mark.parametrize("elevation, aspect", [(50.0, 16 / 9), (20.0, 16 / 9), (80.0, 4 / 3), (30.0, 0.75)])
def test_framing_leaves_room_around_the_subject(elevation, aspect):
    """Every point of the subject projects inside the frame with the margin free, and the tightest side touches
    it: a wide bowl seen from above keeps its rim off the frame's top edge, whatever its size."""
    from nodes.export.mitsuba_scene import Camera, look_at
    from nodes.shapes import shape

    for size in (20.0, 42.0):
        bowl = shape.call(kind="bowl", size=size, depth=0.8 * size, wall=3.0, resolution=3)["mesh"]
        camera = Camera(elevation, 20.0, 35.0, 0.1)
        origin, target = look_at(bowl.vertices, camera, aspect)
        forward = (target - origin) / np.linalg.norm(target - origin)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        d = bowl.vertices - origin
        depth = d @ forward
        tan_x = np.tan(np.radians(camera.fov) / 2)
        u, v = (d @ right) / (depth * tan_x), (d @ up) / (depth * tan_x / aspect)
        assert (depth > 0).all()
        extent = max(np.abs(u).max(), np.abs(v).max())
        assert extent == pytest.approx(0.9, abs=1e-6)  # 10 % of the half-frame free on the tightest side
        assert abs(u.max() + u.min()) < 1e-3 and abs(v.max() + v.min()) < 1e-3  # centred


def test_an_offset_moves_the_subject_to_a_third_of_the_frame_and_keeps_it_in():
    """With ``offset`` (−1/3, 0) the subject's projected extent is centred on the left third line, inside the frame
    with the margin free, as large as that leaves room for."""
    from nodes.export.mitsuba_scene import Camera, look_at
    from nodes.shapes import shape

    bowl = shape.call(kind="bowl", size=42.0, depth=34.0, wall=3.0, resolution=3)["mesh"]

    def projected(camera):
        origin, target = look_at(bowl.vertices, camera, 16 / 9)
        forward = (target - origin) / np.linalg.norm(target - origin)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        d = bowl.vertices - origin
        tan_x = np.tan(np.radians(camera.fov) / 2)
        return (d @ right) / ((d @ forward) * tan_x), (d @ up) / ((d @ forward) * tan_x * 9 / 16)

    u, v = projected(Camera(40.0, 20.0, 20.0, 0.1, offset=(-1 / 3, 0.0)))
    assert 0.5 * (u.max() + u.min()) == pytest.approx(-1 / 3, abs=0.01)  # centred on the left third line
    # the margin free on every side, but for the move's parallax (the nearer points shift a little more)
    assert u.min() > -0.92 and abs(v).max() <= 0.92
    # as large as the room allows: on its tightest side (here the left, 1/3 nearer the frame's edge) it touches
    assert max(-u.min(), abs(v).max()) == pytest.approx(0.9, abs=0.02)


def test_the_denoiser_keeps_the_key_lights_glints(shaded):
    """Glints of the key light on the wet eggs and the glaze survive denoising: the denoised preview's highlight
    energy (sRGB luminance above the 99.5th percentile of a 64-spp render without denoising, summed) keeps at
    least a third of the reference's. The denoiser erased every glint when they were a few bright samples of the
    path-traced pass (energy 0); the glints' pass is added after denoising. Counted on the eggs and the glaze:
    the white rice reaches the threshold too, and there what the 64-spp reference has over it is mostly its
    sampling noise, which the denoiser is right to remove (rice 523 in the reference, 33 denoised; the rest 266
    and 214)."""
    from nodes.export.mitsuba_scene import Camera

    from .test_studio import shows

    weights = np.array([0.2126, 0.7152, 0.0722])
    reference = _render(shaded, width=160, height=90, samples=64, denoise=False) @ weights
    denoised = _render(shaded, width=160, height=90, samples=12) @ weights
    threshold = np.percentile(reference, 99.5)
    p = preview.resolve_params({})
    camera = Camera(p["elevation"], p["azimuth"], p["fov"], p["margin"], p["f_stop"], p["focus"])
    not_rice = ~shows(shaded, camera, 160, 90, p["sun_direction"], "rice")

    def energy(luminance):
        return np.maximum(luminance - threshold, 0.0)[not_rice].sum()

    assert energy(reference) > 0
    assert energy(denoised) > energy(reference) / 3


def test_the_studios_ambient_lights_the_preview_and_shades_does_not(shaded):
    """The preview's ambient is its own parameter (the studio's walls); shade's ambient lit only the baked vertex
    colours, so a sweep of it left the preview's bytes unchanged: it is now named for what it does."""
    from pathlib import Path

    from nodegraph.api import default_registry, load_recipe
    from nodegraph.errors import RecipeError
    from nodes.shading import shade

    dark, lit = (_render(shaded, ambient=a).astype(float).mean() for a in (0.0, 0.5))
    assert lit > dark + 5.0
    assert "ambient" not in shade.params and "baked_ambient" in shade.params
    recipe = Path(__file__).resolve().parents[2] / "graphs" / "ikura_don.yaml"
    with pytest.raises(RecipeError, match="unknown parameter 'ambient' for shade.*baked_ambient"):
        load_recipe(recipe, default_registry(), ["shade.ambient=0.6"])


def test_the_default_samples_give_the_same_bytes(shaded):
    """The default preview's samples: 3 since issue 27's second cut (5 before: 82 → 55 CPU s; then 5 → 3 with no
    light sampling inside the media and 2-spp glints: 58.5 → 35.6 CPU s on the main job, −0.6 dB / −0.036 SSIM in its
    hardest window against 256 spp; docs/accuracy.md, "Preview cost"), and the same bytes twice at that count. On
    this small synthetic frame (160 × 90) fewer samples sit further from 64 spp (5 against 8: mean absolute
    difference 5.9 against 4.8 of 255), which is why the main job's window, not this scene, priced the change."""
    samples = preview.resolve_params({})["samples"]
    assert samples == 3
    first = _render(shaded, width=160, height=90, samples=samples)
    assert np.array_equal(_render(shaded, width=160, height=90, samples=samples), first)


def test_the_denoisers_guides_are_a_one_sample_pass(shaded, monkeypatch):
    """Albedo and normals for OIDN come from a pass of 1 spp (was 2; issue 27: ≈ 0.9 CPU s less on the main job,
    its eggs window against 256 spp 17.89 dB at 1 against 17.86 at 2; docs/accuracy.md, "Preview cost"); the
    colour pass keeps the preview's samples."""
    import mitsuba as mi

    passes = []
    render = mi.render

    def recording(scene, *args, integrator=None, spp=0, **kwargs):
        passes.append(("guides" if integrator is not None else "colour or glints", spp))
        return render(scene, *args, integrator=integrator, spp=spp, **kwargs)

    monkeypatch.setattr(mi, "render", recording)
    _render(shaded, width=64, height=48, samples=3)
    assert ("guides", 1) in passes and ("colour or glints", 0) in passes  # 0: the scene's sampler, 3 spp


def test_the_glints_pass_renders_only_where_a_glint_can_be(shaded, monkeypatch):
    """The glints' pass traces only the window of the film that the subject's hull, widened by the lens's blur,
    covers (``mitsuba_scene.glints_window``; on the main job 58 % of the frame, 2.3 → 1.6 CPU s): every glint of a
    whole-frame pass lies inside it, and the preview's passes render that window, not the whole film."""
    import tempfile
    from pathlib import Path

    import mitsuba as mi

    from nodes.export import mitsuba_scene as ms

    params = preview.resolve_params({})
    camera = ms.Camera(params["elevation"], params["azimuth"], params["fov"], params["margin"], 8.0, params["focus"])
    width, height, sun = 160, 90, params["sun_direction"]
    mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory() as folder:
        description, set_up = ms._described(
            shaded, Path(folder), camera, width, height, 2, sun, None, None, True, params["ambient"]
        )
        window = ms.glints_window(set_up, camera, width, height, ms.glints_core(description))
        whole = np.asarray(mi.render(mi.load_dict(ms.highlight_dict(shaded, description), optimize=False)))
    assert window is not None and window.width * window.height < 0.9 * width * height
    ys, xs = np.nonzero(whole[..., :3].max(axis=2) > 0)
    assert len(xs) > 0  # the small scene glints
    assert xs.min() >= window.x and xs.max() < window.x + window.width
    assert ys.min() >= window.y and ys.max() < window.y + window.height
    shapes = []
    render = mi.render

    def recording(scene, *args, **kwargs):
        out = render(scene, *args, **kwargs)
        shapes.append(np.asarray(out).shape[:2])
        return out

    monkeypatch.setattr(mi, "render", recording)
    ms.render_layers(shaded, camera, width, height, 2, sun, subsurface=True)
    assert (height, width) in shapes and min(h * w for h, w in shapes) < 0.9 * width * height


def test_the_denoisers_albedo_tells_the_eggs_from_the_rice(shaded, monkeypatch):
    """OIDN's albedo guide gives each element its colour: the eggs red (what light keeps through them), the rice
    pale (what it scatters back). Mitsuba's own albedo of a dielectric skin is its Fresnel reflection, ≈ 0.03 grey
    for eggs and rice alike, and the denoiser spread the eggs' red over the rice between them (docs/look.md, "Side
    by side with Blender": the rice between the eggs 128 / 58 / 40 denoised against 149 / 75 / 59 at 128 spp)."""
    import pyoidn

    from nodes.export.mitsuba_scene import Camera

    from .test_studio import shows

    guides = []
    denoise = pyoidn.denoise

    def recording(color, albedo=None, **kwargs):
        guides.append(np.array(albedo))
        return denoise(color, albedo=albedo, **kwargs)

    monkeypatch.setattr(pyoidn, "denoise", recording)
    width, height = 160, 90
    _render(shaded, width=width, height=height, samples=2, subsurface=True)
    p = preview.resolve_params({})
    camera = Camera(p["elevation"], p["azimuth"], p["fov"], p["margin"], p["f_stop"], p["focus"])
    egg, rice = (shows(shaded, camera, width, height, p["sun_direction"], n) for n in ("ikura_membrane", "rice"))
    assert egg.sum() > 50 and rice.sum() > 50
    albedo = guides[-1]
    egg_red, egg_green, _ = np.median(albedo[egg], axis=0)
    rice_rgb = np.median(albedo[rice], axis=0)
    # a red-orange egg (the tints run to light orange, materials.EGG_HUE_SPREAD), not a grey skin (green ≈ red)
    assert egg_red > 0.5 and egg_green < 0.45 * egg_red
    assert rice_rgb.min() > 0.5  # pale rice


def _defocused_spheres():
    """Two spheres under a glossy clear coat (roughness 0.15): a small one near the camera, in focus (the lens
    focuses on the subject's nearest point), and a large one 120 mm behind it, far out of focus at f/16."""
    from nodegraph.values import Mesh
    from nodes.elements.grain_shapes import icosphere
    from nodes.export.mitsuba_scene import Camera
    from nodes.values import Material, ShadedScene

    vertices, faces = icosphere(4)
    elevation, azimuth = np.radians(30.0), np.radians(20.0)
    view = np.array([np.sin(azimuth) * np.cos(elevation), -np.cos(azimuth) * np.cos(elevation), np.sin(elevation)])
    spheres = [(np.zeros(3), 6.0), (-120.0 * view + np.array([30.0, 0.0, 0.0]), 20.0)]
    meshes = [Mesh(vertices * radius + centre, faces, normals=vertices.copy()) for centre, radius in spheres]
    glossy = Material(name="glossy", base_color=(0.05, 0.05, 0.05), clearcoat=1.0, clearcoat_roughness=0.15, ior=1.5)
    return ShadedScene(meshes, (glossy,), np.zeros(2, np.int32)), Camera(30.0, 20.0, 35.0, 0.1, 16.0, 0.0)


def test_the_oiled_table_shows_the_keys_core_as_a_sheen(shaded):
    """On the table the glints' pass lets the boards reflect the key's bright core by their gloss
    (``backdrop_gloss``), as Cycles' glossy table does, over the whole film: the sheen falls on the boards
    outside the subject's window, which the black table of the paper sweep's rule left dark."""
    import tempfile
    from pathlib import Path

    import mitsuba as mi

    from nodes.export import mitsuba_scene as ms

    params = preview.resolve_params({})
    camera = ms.Camera(params["elevation"], params["azimuth"], params["fov"], params["margin"], 8.0, params["focus"])
    width, height, sun = 160, 90, params["sun_direction"]
    mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory() as folder:
        description, set_up = ms._described(
            shaded, Path(folder), camera, width, height, 2, sun, None, None, True, params["ambient"], "table"
        )
        window = ms.glints_window(set_up, camera, width, height, ms.glints_core(description))
        whole = np.asarray(mi.render(mi.load_dict(ms.highlight_dict(shaded, description), optimize=False)))
    outside = np.ones((height, width), bool)
    outside[window.y : window.y + window.height, window.x : window.x + window.width] = False
    assert whole[..., :3].max(axis=2)[outside].mean() > 1e-3  # 0 on a black table


def test_an_out_of_focus_glint_is_a_smooth_disc_not_dots(tmp_path):
    """The key's glint on a sphere far out of focus is a blur disc. The glints' pass sampled it through the thin lens
    at 2 spp (``HIGHLIGHT_SPP``), so each pixel of the disc saw the glint or not: a few bright dots (here 30
    isolated pixels, 4× their neighbourhood's mean, in the far sphere's half of the frame, on the old code; the
    session-42 fix was to give the bowl's glaze no glints). The pass is now sharp, through a pinhole, and each glint
    pixel spread over its circle of confusion (``mitsuba_scene.defocus``): no dot, and the half frame, smoothed over
    5 × 5 pixels, within 25 % (L1, relative) of what the lens converges to (the pass through the lens at 256 spp):
    10 % against 1,024 spp, where 2 spp through the lens were 58 % off."""
    import mitsuba as mi
    from scipy.ndimage import uniform_filter

    from nodes.export import mitsuba_scene as ms

    scene, camera = _defocused_spheres()
    width, height, sun = 160, 90, (-0.45, -0.6, 0.75)
    weights = np.array([0.2126, 0.7152, 0.0722], np.float32)
    glints = ms.render_layers(scene, camera, width, height, 2, sun).highlights @ weights
    mi.set_variant("scalar_rgb")
    description = ms.scene_dict(scene, tmp_path, camera, width, height, 2, sun)
    lens = ms.highlight_dict(scene, description)
    lens["sensor"] = description["sensor"] | {"sampler": {"type": ms.SAMPLER, "sample_count": 256}}
    lens["integrator"] = {"type": "path", "max_depth": 2}
    converged = np.asarray(mi.render(mi.load_dict(lens, optimize=False), seed=1))[..., :3] @ weights
    converged *= np.float32(ms.EXPOSURE)
    far = np.s_[:, width // 2 :]  # the far sphere's half of the frame
    assert converged[far].sum() > 10.0  # it has a glint, spread wide
    neighbours = (uniform_filter(glints.astype(np.float64), 5) * 25 - glints) / 24
    dots = (glints > 4.0 * neighbours) & (glints > 0.05 * converged[far].max())
    assert dots[far].sum() == 0
    smooth, truth = (uniform_filter(np.asarray(x, np.float64), 5)[far] for x in (glints, converged))
    assert np.abs(smooth - truth).sum() < 0.25 * truth.sum()


def test_the_glints_blur_keeps_a_glints_light_unless_a_sharper_nearer_object_covers_it():
    """``bokeh.scatter_discs``: a glint pixel spread over its circle of confusion keeps its light (the disc sums to
    it, round: no pixel of it brighter than another but at the anti-aliased edge); a pixel in focus stays as it is;
    an object nearer than the glint and in focus covers the part of the disc it is on, one as blurred as the glint
    covers nothing (docs/look.md, "Bokeh, not dots")."""
    from nodes.export.bokeh import scatter_discs

    glints = np.zeros((41, 41, 3), np.float32)
    glints[20, 20] = (3.0, 2.0, 1.0)
    glints[2, 2] = (1.0, 1.0, 1.0)  # in focus
    depth = np.full((41, 41), 100.0, np.float32)
    radius = np.full((41, 41), 8.0, np.float32)
    radius[2, 2] = 0.3
    out = scatter_discs(glints, depth, radius)
    assert out[2, 2].tolist() == [1.0, 1.0, 1.0]
    disc = out.copy()
    disc[2, 2] = 0.0
    assert np.allclose(disc.sum(axis=(0, 1)), (3.0, 2.0, 1.0), rtol=1e-5)
    inside = np.hypot(*np.mgrid[-20:21, -20:21]) <= 7.5
    assert np.ptp(disc[inside, 0]) < 1e-6 and disc[~(np.hypot(*np.mgrid[-20:21, -20:21]) < 8.5), 0].max() == 0.0
    near = depth.copy()
    near[:, :20] = 50.0  # the left half nearer
    for blur, kept in ((0.0, 0.5), (8.0, 1.0)):
        r = radius.copy()
        r[:, :20] = blur
        r[2, 2] = 0.3
        covered = scatter_discs(glints, near, r)
        covered[2, 2] = 0.0
        assert covered[:, :20, 0].sum() == pytest.approx(0.0 if blur == 0.0 else disc[:, :20, 0].sum(), abs=1e-6)
        assert covered[..., 0].sum() == pytest.approx(3.0 * kept, rel=0.1)


def test_the_denoisers_albedo_guide_shows_each_eggs_eye(shaded):
    """Issue 48: at 3 spp OIDN smeared each egg's pale eye into its red: the guide gave the whole membrane one
    colour. It now gives each hit the colour of its triangle's own transmittance (paler over the eye), so the
    guide varies across an egg; with no per-vertex transmittance it is one colour per tint."""
    from nodes.export import mitsuba_scene as ms

    camera = ms.Camera(elevation=60.0, azimuth=20.0, fov=35.0, margin=0.05)

    def guide(scene):
        layers = ms.render_layers(scene, camera, 64, 48, 1, (-0.8, 0.15, 0.58))
        return layers.albedo

    eyes = guide(shaded)
    flat = guide(dataclasses.replace(shaded, transmittance=()))
    eggs = (flat[..., 0] > 2 * flat[..., 1] + 0.1) & (flat[..., 0] > 0.3)  # a red guide: an egg's membrane
    assert eggs.sum() > 20
    distinct = lambda albedo: len(np.unique(np.round(albedo[eggs], 4), axis=0))  # noqa: E731
    assert distinct(flat) <= len([m for m in shaded.materials if m.name.startswith("ikura_membrane")])
    assert distinct(eyes) > 3 * distinct(flat)
    assert eyes[eggs][:, 1].max() > flat[eggs][:, 1].max() + 0.05  # paler (more green kept) over an eye
