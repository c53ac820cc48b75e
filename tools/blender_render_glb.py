"""Run by the Blender venv's Python (bpy 4.5): render an exported .glb with Cycles in the preview's studio, for a
side-by-side with our Mitsuba preview (tools/blender_side_by_side.py writes SETTINGS.json).

    python blender_render_glb.py SCENE.glb SETTINGS.json RENDER.png

The repository's add-on reads the look the exporter wrote (``blender/nodegraph_import``). SETTINGS.json is the
preview's own studio as numbers (``nodes.export.mitsuba_scene.studio_description``; bpy's venv cannot import the
project: it pins numpy 1.26), in the scene's millimetres, built here in the .glb's metres: the camera and thin lens,
the softbox key, fill and rim light as emitting rectangles of the same radiance facing the subject, the dim ambient
as the world, the matte seamless backdrop, the glints' core as a small emitting sphere seen only in glossy
reflections after one bounce (as the preview's glints' pass), the same exposure, the same path depth for every kind
of bounce; Blender's 'Standard' view transform (sRGB, no filmic curve); no Filter Glossy, so
Cycles is as unbiased as the preview's path tracer.
"""

import json
import sys
from pathlib import Path

import bpy
import numpy as np
from mathutils import Matrix, Vector

REPO = Path(__file__).resolve().parents[1]
MM = 1e-3  # the .glb's root node scales our millimetres to metres


def emission_material(name: str, radiance: float, glossy_only: bool = False):
    """An emission of ``radiance`` (Cycles: strength 1 seen directly is pixel value 1, as the preview's radiance)
    from the front faces only, as the preview's one-sided area lights (the back faces: no shader, black)."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = radiance
    mix = nodes.new("ShaderNodeMixShader")
    geometry = nodes.new("ShaderNodeNewGeometry")
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(emission.outputs["Emission"], mix.inputs[1])
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(mix.outputs["Shader"], output.inputs["Surface"])
    return material


def one_bounce(material, radiance: float) -> None:
    """The emission of ``material`` (``emission_material``) only to rays after one bounce off the camera's first
    hit: the preview's glints' pass is one bounce (``mitsuba_scene.highlight_dict``), every surface reflecting only
    its gloss. Seen at any depth, the core (radiance 60, more power than the key) lit the rice again through every
    gloss it met on the way (a grain's skin, an egg's)."""
    tree = material.node_tree
    path = tree.nodes.new("ShaderNodeLightPath")
    first = tree.nodes.new("ShaderNodeMath")
    first.operation = "LESS_THAN"
    first.inputs[1].default_value = 1.5
    strength = tree.nodes.new("ShaderNodeMath")
    strength.operation = "MULTIPLY"
    strength.inputs[1].default_value = radiance
    tree.links.new(path.outputs["Ray Depth"], first.inputs[0])
    tree.links.new(first.outputs[0], strength.inputs[0])
    emission = next(n for n in tree.nodes if n.type == "EMISSION")
    tree.links.new(strength.outputs[0], emission.inputs["Strength"])


def link(obj, camera=True, diffuse=True):
    obj.visible_camera = camera
    obj.visible_diffuse = diffuse
    obj.visible_transmission = diffuse
    obj.visible_volume_scatter = diffuse
    bpy.context.scene.collection.objects.link(obj)
    return obj


def rectangle_light(name, light, target):
    """An emitting rectangle of the light's half sizes at its centre, its front (+z) turned to ``target``."""
    hx, hy = (h * MM for h in light["half_sizes"])
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([(-hx, -hy, 0), (hx, -hy, 0), (hx, hy, 0), (-hx, hy, 0)], [], [(0, 1, 2, 3)])
    mesh.materials.append(emission_material(name, light["radiance"]))
    obj = bpy.data.objects.new(name, mesh)
    centre = Vector(light["center"]) * MM
    forward = Vector(target) * MM - centre
    obj.matrix_world = Matrix.Translation(centre) @ forward.to_track_quat("Z", "Y").to_matrix().to_4x4()
    return link(obj)


def main() -> None:
    source, settings_path, out = (Path(a) for a in sys.argv[-3:])
    s = json.loads(settings_path.read_text())
    bpy.ops.wm.read_factory_settings(use_empty=True)
    import addon_utils

    sys.path.insert(0, str(REPO / "blender"))
    addon_utils.enable("nodegraph_import", default_set=True, handle_error=None)
    bpy.ops.import_scene.gltf(filepath=str(source))
    scene = bpy.context.scene
    scene.unit_settings.scale_length = 1.0

    c = s["camera"]
    origin, target = Vector(c["origin"]) * MM, Vector(c["target"]) * MM
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.sensor_fit = "HORIZONTAL"
    camera.data.sensor_width = 36.0
    camera.data.angle = np.radians(c["fov"])
    size = (origin - target).length
    camera.data.clip_start, camera.data.clip_end = size * 1e-3, size * 1e3
    camera.matrix_world = Matrix.Translation(origin) @ (target - origin).to_track_quat("-Z", "Y").to_matrix().to_4x4()
    if c["f_stop"] > 0:  # a full-frame thin lens: aperture radius = focal length / (2 f), as the preview's
        camera.data.dof.use_dof = True
        camera.data.dof.aperture_fstop = c["f_stop"]
        camera.data.dof.focus_distance = c["focus_distance"] * MM
    scene.collection.objects.link(camera)
    scene.camera = camera

    world = bpy.data.worlds.new("ambient")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = s["ambient"]
    scene.world = world
    for name, light in s["lights"].items():
        rectangle_light(name, light, s["target"])
    glints = s["glints"]
    bpy.ops.mesh.primitive_uv_sphere_add(radius=glints["radius"] * MM, location=Vector(glints["center"]) * MM)
    core = bpy.context.active_object
    core.data.materials.append(emission_material("glints", glints["radiance"]))
    one_bounce(core.data.materials[0], glints["radiance"])
    core.visible_camera = core.visible_diffuse = core.visible_transmission = core.visible_volume_scatter = False
    core.visible_shadow = False

    b = s["backdrop"]
    mesh = bpy.data.meshes.new("backdrop")
    mesh.from_pydata([tuple(v * MM for v in p) for p in b["vertices"]], [], [tuple(f) for f in b["faces"]])
    material = bpy.data.materials.new("backdrop")
    material.use_nodes = True
    principled = material.node_tree.nodes["Principled BSDF"]
    if "texture" in b:  # the table: oak boards (the preview's own texture), oiled, its tile repeated by the UVs
        layer = mesh.uv_layers.new(name="UVMap")
        for loop in mesh.loops:
            layer.data[loop.index].uv = b["uv"][loop.vertex_index]
        image = material.node_tree.nodes.new("ShaderNodeTexImage")
        image.image = bpy.data.images.load(b["texture"])
        image.extension = "REPEAT"
        material.node_tree.links.new(image.outputs["Color"], principled.inputs["Base Color"])
        principled.inputs["Roughness"].default_value = b["roughness"]
        principled.inputs["Specular IOR Level"].default_value = 0.5
    else:  # the seamless sweep: matte paper
        principled.inputs["Base Color"].default_value = (*b["color"], 1.0)
        principled.inputs["Roughness"].default_value = 1.0
        principled.inputs["Specular IOR Level"].default_value = 0.0
    mesh.materials.append(material)
    scene.collection.objects.link(bpy.data.objects.new("backdrop", mesh))

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = s["samples"]
    scene.cycles.seed = s.get("seed", 0)
    scene.cycles.max_bounces = s["max_depth"]
    scene.cycles.transmission_bounces = s["max_depth"]
    scene.cycles.volume_bounces = s["max_depth"]
    # the preview's path depth counts every bounce alike: no smaller cap per kind (Cycles' default 4 diffuse and 4
    # glossy ended the walks that reflect inside a grain: a grain-thick slab of rice under a white sky reflected 2–3 %
    # less than without them and than a random walk at that depth; docs/look.md, "Side by side with Blender")
    scene.cycles.diffuse_bounces = scene.cycles.glossy_bounces = s["max_depth"]
    scene.cycles.transparent_max_bounces = s["max_depth"]
    # no Filter Glossy (Cycles' default 1.0 blurs glossy and refractive closures after a blurry bounce, a bias
    # against noise): with it the red light through the eggs onto the rice between them was lost (rice 91 against
    # 128 of 255 in red, 128 spp without denoising; the preview's unbiased path tracer: 141; docs/look.md)
    scene.cycles.blur_glossy = 0.0
    scene.cycles.use_denoising = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.exposure = float(np.log2(s["exposure"]))
    scene.render.resolution_x, scene.render.resolution_y = s["width"], s["height"]
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = str(out)
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main()
