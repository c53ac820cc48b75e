"""The preview's procedural studio (``nodes.export.studio``): key, fill and rim lights, the seamless backdrop, the
thin lens, and the framing measured on the rendered picture."""

import tempfile
from pathlib import Path

import numpy as np
import pytest


def _description(shaded, tmp_path, camera=None, light=(-0.45, -0.6, 0.75), width=64, height=48):
    import mitsuba as mi

    from nodes.export.mitsuba_scene import Camera, scene_dict

    mi.set_variant("scalar_rgb")
    camera = camera or Camera(50.0, 20.0, 35.0, 0.1, 5.6, 0.35)
    return scene_dict(shaded, tmp_path, camera, width, height, 2, light)


def _frame(description):
    """(origin, forward) of the sensor."""
    m = np.array(description["sensor"]["to_world"].matrix, np.float64)
    return m[:3, 3], m[:3, 2]


def _light(description, name):
    """(centre, emitting direction, radiance, half sizes) of a rectangle light."""
    m = np.array(description[name]["to_world"].matrix, np.float64)
    return m[:3, 3], m[:3, 2], description[name]["emitter"]["radiance"]["value"], np.linalg.norm(m[:3, :2], axis=0)


def test_projected_solid_angle_matches_a_numerical_integral():
    """∫cos θ cos θ′ / r² over a face-on rectangle = ∬ d² / (x² + y² + d²)² dx dy, by the midpoint rule."""
    from nodes.export.studio import projected_solid_angle

    for a, b, d in [(1.0, 0.5, 2.0), (3.0, 3.0, 1.0), (0.1, 0.2, 5.0)]:
        n = 800
        x = (np.arange(n) + 0.5) / n * 2 * a - a
        y = (np.arange(n) + 0.5) / n * 2 * b - b
        xx, yy = np.meshgrid(x, y)
        numeric = (d * d / (xx**2 + yy**2 + d * d) ** 2).sum() * (2 * a / n) * (2 * b / n)
        assert projected_solid_angle(a, b, d) == pytest.approx(numeric, rel=1e-4)


def test_the_studio_has_a_key_a_fill_a_rim_light_and_a_backdrop(shaded, tmp_path):
    """A food photographer's set: the key along the key-light direction, the fill on the camera's side two stops
    under it, the rim behind the subject (away from the camera) and above it, each aimed at the subject and
    giving its irradiance there; a dim ambient; the old uniform sky and flat table are gone."""
    from nodes.export import studio

    light = np.array([-0.45, -0.6, 0.75])
    d = _description(shaded, tmp_path, light=light)
    assert {"key", "fill", "rim", "backdrop", "sky"} <= set(d) and "table" not in d
    origin, forward = _frame(d)
    key_centre, key_aim, *_ = _light(d, "key")
    assert -key_aim @ (light / np.linalg.norm(light)) == pytest.approx(1.0, abs=1e-6)
    # the subject's centre, where the camera aims: the key's axis crosses the camera's axis there
    w = key_centre - origin
    b = key_aim @ forward
    s, t = np.linalg.solve([[1.0, -b], [b, -1.0]], [-(w @ key_aim), -(w @ forward)])
    target = key_centre + s * key_aim
    assert np.linalg.norm(target - (origin + t * forward)) < 1e-6 * np.linalg.norm(w)
    camera_side = (origin - target) / np.linalg.norm(origin - target)
    irradiance = {}
    for name in ("key", "fill", "rim"):
        centre, aim, radiance, half = _light(d, name)
        distance = np.linalg.norm(target - centre)
        assert aim @ (target - centre) / distance == pytest.approx(1.0, abs=1e-6), name  # aimed at the subject
        irradiance[name] = radiance * studio.projected_solid_angle(*half, distance)
        assert d[name]["emitter"]["sampling_weight"] == pytest.approx(irradiance[name], rel=1e-5)
    assert irradiance["key"] == pytest.approx(studio.KEY_IRRADIANCE, rel=1e-5)
    assert 3.0 < irradiance["key"] / irradiance["fill"] < 5.0  # two stops
    fill = _light(d, "fill")[0] - target
    rim = _light(d, "rim")[0] - target
    horizontal = np.array([camera_side[0], camera_side[1], 0.0])
    assert fill @ horizontal > 0 and rim @ horizontal < 0 and rim[2] > 0  # fill in front, rim behind and above
    assert d["sky"]["radiance"]["value"] * np.pi < 0.1 * irradiance["key"]  # a dim studio, not a bright sky


def test_the_table_is_oak_boards_under_the_subject_in_both_renderers(shaded, tmp_path):
    """Setting 'table': a flat rectangle at the subject's lowest point, up-facing, far wider than the subject,
    textured with the oak boards (dark latewood bands in lighter earlywood, averaging the oiled oak's colour); the
    Blender side-by-side gets the same corners, UVs and texture."""
    import mitsuba as mi
    from PIL import Image as PILImage

    from nodes.export import studio
    from nodes.export.mitsuba_scene import Camera, scene_dict, studio_description

    mi.set_variant("scalar_rgb")
    camera = Camera(35.0, 20.0, 20.0, 0.1, 5.6, 0.25)
    d = scene_dict(shaded, tmp_path, camera, 64, 48, 2, (-0.8, 0.15, 0.58), setting="table")
    table = d["backdrop"]
    assert table["type"] == "rectangle" and table["bsdf"]["base_color"]["type"] == "bitmap"
    m = np.array(table["to_world"].matrix, np.float64)
    points = np.concatenate([mesh.vertices for mesh in shaded.meshes])
    assert m[2, 3] <= points[:, 2].min() and np.allclose(m[:3, 2], [0, 0, 1])  # under everything, facing up
    assert min(np.linalg.norm(m[:3, 0]), np.linalg.norm(m[:3, 1])) > 10 * np.ptp(points[:, :2], axis=0).max()
    texture = np.asarray(PILImage.open(table["bsdf"]["base_color"]["filename"]), np.float64) / 255
    linear = np.where(texture <= 0.04045, texture / 12.92, ((texture + 0.055) / 1.055) ** 2.4)
    assert np.allclose(linear.reshape(-1, 3).mean(axis=0), studio.TABLE_COLOR, rtol=0.2)
    green = linear[..., 1]
    rows = green.mean(axis=0)  # across the boards: the joints dark, the grain a low contrast
    assert rows.min() < 0.6 * rows.mean() and 0.03 < green.std() / green.mean() < 0.15
    described = studio_description(shaded, camera, 64, 48, (-0.8, 0.15, 0.58), setting="table")["backdrop"]
    corners = np.array(described["vertices"]) - m[:3, 3]
    assert np.allclose(np.abs(corners @ m[:3, 0]) / np.linalg.norm(m[:3, 0]) ** 2, 1.0)
    assert described["texture"] == "table.png" and described["uv"][2][0] > 1  # the tile repeats
    assert "table" not in scene_dict(shaded, tmp_path, camera, 64, 48, 2, (-0.8, 0.15, 0.58))["backdrop"]["type"]


def test_the_backdrop_sweeps_up_behind_the_subject():
    """The sweep is flat under and in front of the subject, curves up only behind it (seen from the camera),
    with no step (seamless), and every face turns its lit side to the subject."""
    from nodes.export.studio import BACKDROP_BEHIND, backdrop_mesh

    target, radius, floor = np.array([1.0, 2.0, 3.0]), 10.0, -5.0
    view = np.array([0.3, -0.8, 0.6])  # towards the camera
    vertices, faces, normals = backdrop_mesh(target, radius, floor, view)
    front = np.array([view[0], view[1], 0.0]) / np.linalg.norm(view[:2])
    behind = (vertices - target) @ -front
    height = vertices[:, 2] - floor
    assert height.min() == pytest.approx(0.0) and (height[behind <= BACKDROP_BEHIND * radius + 1e-9] < 1e-9).all()
    assert height.max() > 10 * radius and behind[height > 1e-6].min() > BACKDROP_BEHIND * radius
    tri = vertices[faces]
    geometric = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (np.einsum("ij,ij->i", geometric, target - tri.mean(axis=1)) > 0).all()
    # seamless: consecutive faces along the profile turn by a few degrees at most
    unit = geometric / np.linalg.norm(geometric, axis=1, keepdims=True)
    half = len(faces) // 2
    turns = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", unit[: half - 1], unit[1:half]), -1, 1)))
    assert turns.max() < 10.0 and np.allclose(np.linalg.norm(normals, axis=1), 1.0)


def test_the_lens_focuses_on_the_front_of_the_subject(shaded, tmp_path):
    """A thin lens at the f-number's aperture (focal length of a full-frame camera at the field of view / 2N),
    focused between the subject's nearest point and its middle; f-number 0 is a pinhole."""
    from nodes.export import studio
    from nodes.export.mitsuba_scene import Camera

    d = _description(shaded, tmp_path, Camera(50.0, 20.0, 35.0, 0.1, 4.0, 0.3))
    sensor = d["sensor"]
    assert sensor["type"] == "thinlens"
    assert sensor["aperture_radius"] == pytest.approx(18.0 / np.tan(np.radians(17.5)) / 8.0)
    origin, forward = _frame(d)
    depths = np.concatenate([m.vertices for m in shaded.meshes]) @ forward - origin @ forward
    assert depths.min() < sensor["focus_distance"] < np.median(depths)
    assert studio.focal_length(35.0) == pytest.approx(57.1, abs=0.1)
    pinhole = _description(shaded, tmp_path, Camera(50.0, 20.0, 35.0, 0.1, 0.0, 0.3))
    assert pinhole["sensor"]["type"] == "perspective" and "aperture_radius" not in pinhole["sensor"]


@pytest.mark.parametrize("elevation", [50.0, 20.0])
@pytest.mark.parametrize("bowl_size", [12.0, 30.0])
def test_the_rendered_subject_keeps_room_around_it(tmp_path, elevation, bowl_size):
    """On the rendered picture (a mask of the subject: its depth seen through the preview's own camera, without the
    backdrop), the bowl's rim stays off the frame's edges: about ``margin`` (10 %) of the half-frame is free on the
    tightest side, at any bowl size (as after ``--set bowl.size=…``) and elevation."""
    import mitsuba as mi
    from scene_builders import small_food_scene

    from nodes.export.mitsuba_scene import Camera, scene_dict
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade
    from nodes.shapes import shape

    mi.set_variant("scalar_rgb")
    inputs = small_food_scene()
    inputs["scenery"] = [shape.call(kind="bowl", size=bowl_size, depth=0.7 * bowl_size, resolution=2)["container"]]
    scene = shade.call(**inputs, material=cooked_material())
    width, height = 160, 90
    d = scene_dict(scene, tmp_path, Camera(elevation, 20.0, 35.0, 0.1), width, height, 1, (-0.45, -0.6, 0.75))
    subject = {k: v for k, v in d.items() if k.startswith("shape_")}
    mask_scene = mi.load_dict({"type": "scene", "sensor": d["sensor"], **subject})
    depth = np.asarray(mi.render(mask_scene, integrator=mi.load_dict({"type": "aov", "aovs": "z:depth"})))[..., 0]
    rows, cols = np.nonzero(depth > 0)
    free = (
        min(rows.min(), height - 1 - rows.max()) / (height / 2),
        min(cols.min(), width - 1 - cols.max()) / (width / 2),
    )
    assert min(free) == pytest.approx(0.1, abs=0.03)  # the tightest side: the margin, within a pixel or so
    assert max(free) >= 0.1 - 0.03


def _rice_heap(water=15.0):
    """Three layers of cooked grains (capsules 5 × 2 mm lying in a brick pattern, 0.2 mm apart), shaded at
    ``water`` %: a patch of a rice heap on the studio's backdrop."""
    import trimesh

    from nodegraph.values import Mesh
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade
    from nodes.values import Aggregate, ElementLibrary, Placement

    grain = Mesh.from_trimesh(trimesh.creation.capsule(height=3.0, radius=1.0, count=[8, 8]))
    turn = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # the capsule's axis (z) along x
    ix, iy, iz = np.meshgrid(np.arange(4), np.arange(7), np.arange(3), indexing="ij")
    positions = np.stack([5.2 * ix + 2.6 * ((iy + iz) % 2), 2.2 * iy, 1.0 + 2.2 * iz], axis=-1).reshape(-1, 3)
    positions -= [positions[:, 0].mean(), positions[:, 1].mean(), 0.0]
    count = len(positions)
    placement = Placement(
        positions, np.tile([0, 0, 1.0], (count, 1)), rotations=np.tile(turn, (count, 1, 1)), kind_names=("japonica",)
    )
    rice = Aggregate(placement, (ElementLibrary("japonica", (grain,)),))
    return shade.call(aggregates=[rice], material=cooked_material(water_content=water))


def shows(scene, camera, width, height, light, name):
    """Which pixels of the preview's frame show material ``name`` (or its tints, ``<name>_<k>``): the same scene
    with that material green and the rest red, read from the albedo pass."""
    import mitsuba as mi

    from nodes.export.mitsuba_scene import scene_dict

    mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory() as folder:
        d = scene_dict(scene, Path(folder), camera, width, height, 2, light)
        for key, shape in d.items():
            if isinstance(shape, dict) and "bsdf" in shape:
                own = scene.materials[int(key.removeprefix("shape_"))].name if key.startswith("shape_") else ""
                wanted = own == name or own.startswith(name + "_")
                colour = [0.0, 1.0, 0.0] if wanted else [1.0, 0.0, 0.0]
                shape["bsdf"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": colour}}
        d["integrator"] = {"type": "aov", "aovs": "albedo:albedo"}
        albedo = np.asarray(mi.render(mi.load_dict(d), spp=4))
    return albedo[..., 1] > 0.5


def _rice_lab(shaded, width=128, height=72, spp=8):
    """Median CIELAB (L*, a*, b*) of the pixels that show rice in the denoised studio preview (media on), and the
    spread (standard deviation) of their a* and b*: the grains' colour noise."""
    from skimage.color import rgb2lab

    from nodes.export.mitsuba_scene import Camera, render

    camera = Camera(50.0, 20.0, 35.0, 0.1, 5.6, 0.25)
    light = (-0.45, -0.6, 0.75)
    image = render(shaded, camera, width, height, spp, light, subsurface=True)
    rice = shows(shaded, camera, width, height, light, "rice")
    lab = rgb2lab(image[rice][None].astype(np.float64) / 255.0)[0]
    return np.median(lab, axis=0), lab[:, 1:].std(axis=0)


def test_cooked_rice_reads_warm_white_in_the_studio():
    """Cooked rice in a food photograph is a warm white: bright (CIELAB L* ≥ 75), cream (b* 4–12, a* near 0), of
    one colour from grain to grain. Before: grey (L* 69), neutral (b* 2) and mottled with the opal patches of
    the media's colour noise."""
    (lightness, a, b), spread = _rice_lab(_rice_heap())
    print(f"rice L* {lightness:.1f} a* {a:.1f} b* {b:.1f}, spread a* {spread[0]:.1f} b* {spread[1]:.1f}")
    assert lightness >= 75.0
    assert 4.0 <= b <= 12.0 and abs(a) <= 3.0
    assert spread.max() <= 4.0


def test_cooked_rice_converges_in_a_few_samples():
    """The light under a grain's film is sampled at every scattering event (``look.has_film``: the path-traced pass
    passes light through the film unbent, so the medium samples the lights): two 4-spp renders of a rice heap at
    other seeds differ by 0.55 of the rice's mean before any denoiser. Behind a refracting skin no shadow ray
    from inside reaches a light, a path lit the grain only when it left it towards a softbox by chance, and the two
    differed by 1.47: a few bright samples among black ones, which the denoiser made into chalky beads."""
    from nodes.export.mitsuba_scene import Camera, render_layers

    shaded = _rice_heap()
    camera = Camera(50.0, 20.0, 35.0, 0.1)
    light = (-0.45, -0.6, 0.75)
    rice = shows(shaded, camera, 96, 54, light, "rice")
    a, b = (render_layers(shaded, camera, 96, 54, 4, light, seed, subsurface=True).color for seed in (1, 2))
    luminance = np.array([0.2126, 0.7152, 0.0722])
    la, lb = a[rice] @ luminance, b[rice] @ luminance
    difference = np.abs(la - lb).mean() / (0.5 * (la + lb).mean())
    print(f"4-spp renders at two seeds differ by {difference:.3f} of the rice's mean")
    assert difference < 0.8


def test_the_film_pass_gives_rice_its_sheen_and_only_rice():
    """The film over a grain reflects the studio's softboxes in a pass of its own (``highlight_dict`` with
    ``film``), Fresnel's share at the film's roughness, added after the denoiser: the grains facing the key carry
    a broad sheen. Nothing else reflects in it: the path-traced pass already carries every other surface's gloss."""
    import mitsuba as mi

    from nodes.export import mitsuba_scene as ms
    from nodes.export.look import boundary_roughness

    shaded = _rice_heap()
    camera = ms.Camera(50.0, 20.0, 35.0, 0.1)
    light = (-0.45, -0.6, 0.75)
    with tempfile.TemporaryDirectory() as folder:
        description = ms.scene_dict(shaded, Path(folder), camera, 96, 54, 2, light, subsurface=True)
        film = ms.highlight_dict(shaded, description, film=True)
        assert {"key", "fill", "rim"} <= set(film) and film["backdrop"]["bsdf"]["reflectance"]["value"] == [0.0] * 3
        rice = [k for k, v in film.items() if k.startswith("shape_") and v["bsdf"]["type"] != "diffuse"]
        material = shaded.materials[int(rice[0].removeprefix("shape_"))]
        assert len(rice) == 1 and material.name == "rice"
        assert film[rice[0]]["bsdf"]["alpha"] == pytest.approx(boundary_roughness(material) ** 2)
        sheen = np.asarray(mi.render(mi.load_dict(film, optimize=False), spp=ms.FILM_SPP))[..., :3]
    from scipy.ndimage import binary_dilation

    shows_rice = shows(shaded, camera, 96, 54, light, "rice")
    assert sheen[shows_rice].mean() > 0.01 and sheen[~binary_dilation(shows_rice, iterations=2)].max() == 0.0


def test_the_blender_side_by_side_builds_the_previews_own_studio(shaded, tmp_path):
    """The side-by-side script hands Blender the preview's studio as numbers (one description, not a copy): the
    same camera, lens, key, fill and rim (centre, size, radiance), ambient, backdrop and exposure as the Mitsuba
    scene, JSON-serialisable. Before, it handed a sun, a sky and a table from names the studio had removed."""
    import importlib.util
    import json

    from nodes.export import mitsuba_scene as ms
    from nodes.export import studio
    from nodes.export.preview import preview

    spec = importlib.util.spec_from_file_location("side", Path(__file__).parents[2] / "tools/blender_side_by_side.py")
    side = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(side)
    params = preview.resolve_params({"width": 64, "height": 48})
    described = json.loads(json.dumps(side.settings(shaded, params, 8)))
    camera = ms.Camera(params["elevation"], params["azimuth"], params["fov"], params["margin"], params["f_stop"])
    d = _description(shaded, tmp_path, camera=camera, light=params["sun_direction"])
    origin, _ = _frame(d)
    assert np.allclose(described["camera"]["origin"], origin, rtol=1e-6)
    assert described["camera"]["focus_distance"] == pytest.approx(d["sensor"]["focus_distance"])
    assert described["camera"]["aperture_radius"] == pytest.approx(d["sensor"]["aperture_radius"])
    assert set(described["lights"]) == {"key", "fill", "rim"}
    for name, light in described["lights"].items():
        centre, _, radiance, half = _light(d, name)
        assert np.allclose(light["center"], centre, rtol=1e-6) and np.allclose(light["half_sizes"], half, rtol=1e-6)
        assert light["radiance"] == pytest.approx(radiance)
    assert described["ambient"] == studio.AMBIENT and described["backdrop"]["color"] == list(studio.BACKDROP_COLOR)
    assert described["exposure"] == ms.EXPOSURE and described["samples"] == 8


def test_each_membrane_is_rendered_with_its_own_transmittance_per_vertex(shaded, tmp_path):
    """The preview renders each egg's membrane, one closed mesh, with the transmittance each of its vertices keeps
    (``ShadedScene.transmittance``, √ per crossing): paler over the eye."""
    from nodes.export.mitsuba_scene import _shapes

    shapes, _ = _shapes(shaded, tmp_path, subsurface=True)
    membrane = next(k for k, m in enumerate(shaded.materials) if m.name.startswith("ikura_membrane"))
    shape = shapes[f"shape_{membrane}"]
    assert shape["bsdf"]["specular_transmittance"] == {"type": "mesh_attribute", "name": "vertex_color"}
    data = Path(shape["filename"]).read_bytes()
    head, body = data.split(b"end_header\n", 1)
    count = int(head.split(b"element vertex ")[1].split(b"\n")[0])
    rows = np.frombuffer(body[: count * 36], "<f4").reshape(count, 9)  # x y z nx ny nz r g b
    own = np.concatenate([shaded.transmittance[k] for k in np.flatnonzero(shaded.material_of == membrane)])
    assert rows[:, 6:] == pytest.approx(np.sqrt(own), rel=1e-5)
    green = rows[:, 7]
    assert green.max() > 1.5 * green.min()  # the eye's vertices pass more green than the membrane's


def test_the_shade_nodes_key_intensity_reaches_the_preview_and_the_blender_studio(scene_inputs, shaded, tmp_path):
    """``shade.light_intensities`` is the key of the preview too: twice the intensity, twice the key softbox's
    radiance and its glints' in the Mitsuba scene and in the studio the Blender side-by-side builds; the fill, the
    rim and the ambient stay; the default intensity is the studio's own key."""
    from nodes.export.mitsuba_scene import Camera, highlight_dict, studio_description
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade
    from nodes.shading.shade import KEY_INTENSITY

    brighter = shade.call(**scene_inputs, material=cooked_material(), light_intensities=[2 * KEY_INTENSITY])
    assert shaded.key_gain == 1.0 and brighter.key_gain == pytest.approx(2.0)
    base, bright = _description(shaded, tmp_path), _description(brighter, tmp_path)
    assert _light(bright, "key")[2] == pytest.approx(2 * _light(base, "key")[2])
    for name in ("fill", "rim"):
        assert _light(bright, name)[2] == pytest.approx(_light(base, name)[2])
    glint = lambda scene, d: highlight_dict(scene, d)["key"]["emitter"]["radiance"]["value"]
    assert glint(brighter, bright) == pytest.approx(2 * glint(shaded, base))
    camera = Camera(50.0, 20.0, 35.0, 0.1, 5.6, 0.35)
    blender = [studio_description(s, camera, 64, 48, (-0.45, -0.6, 0.75)) for s in (shaded, brighter)]
    assert blender[1]["lights"]["key"]["radiance"] == pytest.approx(2 * blender[0]["lights"]["key"]["radiance"])
    assert blender[1]["glints"]["radiance"] == pytest.approx(2 * blender[0]["glints"]["radiance"])
