"""Run by the Blender venv's Python (bpy 4.5), for benchmarks/slab_optics.py: a slab of one material, 200 mm wide and
H mm thick, under a white sky over the upper hemisphere and black below, seen straight on by an orthographic camera
(2 × 2 px over 1 mm) from above (reflectance) or below (transmittance); Cycles without a denoiser.

    python tools/slab_cycles.py ADDON_DIR LOOK.json KIND H SIDE SPP OUT.json

ADDON_DIR: the folder that holds the add-on (``blender``; an older version's, to measure it).
LOOK.json: the material's ``nodegraph:principled:*`` set (``nodes/export/look.py``), which the repository's add-on
reads (``blender/nodegraph_import``), after what Blender's glTF importer sets for KIND ``membrane`` (base colour,
roughness, transmission, clear coat and its roughness, specular level) or nothing (``rice``: the add-on sets it all).
"""

import json
import sys
from pathlib import Path

import bpy
import numpy as np

MM = 1e-3
DEPTH = 64  # the preview's MAX_DEPTH_MEDIA


def main() -> None:
    addon, look_path, kind, h, side, spp, out = sys.argv[-7:]
    look, h, spp = json.loads(Path(look_path).read_text()), float(h), int(spp)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sys.path.insert(0, addon)
    import nodegraph_import

    bpy.ops.mesh.primitive_cube_add(size=2.0)
    slab = bpy.context.active_object
    slab.scale = (100 * MM, 100 * MM, h / 2 * MM)
    slab.location = (0, 0, -h / 2 * MM)
    material = bpy.data.materials.new(kind)
    material.use_nodes = True
    if kind == "membrane":  # what the glTF importer makes of the membrane's glTF material (gltf_writer)
        inputs = material.node_tree.nodes["Principled BSDF"].inputs
        inputs["Base Color"].default_value = (*look["subsurfaceColor"], 1.0)
        inputs["Roughness"].default_value = look["transmissionRoughness"]
        inputs["Transmission Weight"].default_value = look["transmission"]
        inputs["IOR"].default_value = look["ior"]
        inputs["Coat Weight"].default_value = 1.0
        inputs["Coat Roughness"].default_value = look["coatRoughness"]
        inputs["Specular IOR Level"].default_value = look["specular"]
    for key, value in look.items():
        material[nodegraph_import.PREFIX + key] = value
    nodegraph_import.apply_look(material)
    slab.data.materials.append(material)

    scene = bpy.context.scene
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    tree = world.node_tree
    coordinates, split = tree.nodes.new("ShaderNodeTexCoord"), tree.nodes.new("ShaderNodeSeparateXYZ")
    above = tree.nodes.new("ShaderNodeMath")
    above.operation = "GREATER_THAN"
    above.inputs[1].default_value = 0.0
    tree.links.new(coordinates.outputs["Generated"], split.inputs[0])
    tree.links.new(split.outputs["Z"], above.inputs[0])
    tree.links.new(above.outputs[0], tree.nodes["Background"].inputs["Strength"])
    tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scene.world = world
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 1 * MM
    camera.data.clip_start = 1e-4
    camera.location = (0, 0, 5 * MM if side == "top" else (-h - 5) * MM)
    camera.rotation_euler = (0, 0, 0) if side == "top" else (np.pi, 0, 0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    cycles = scene.cycles
    scene.render.engine = "CYCLES"
    cycles.device, cycles.samples, cycles.seed = "CPU", spp, 1
    cycles.use_denoising = cycles.use_adaptive_sampling = False
    cycles.max_bounces = cycles.transmission_bounces = cycles.volume_bounces = DEPTH
    cycles.diffuse_bounces = cycles.glossy_bounces = cycles.transparent_max_bounces = DEPTH
    cycles.blur_glossy = 0.0
    scene.view_settings.view_transform = "Standard"
    scene.render.resolution_x = scene.render.resolution_y = 2
    scene.render.image_settings.file_format = "OPEN_EXR"
    exr = Path(out).with_suffix(".exr")
    scene.render.filepath = str(exr)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(str(exr))
    pixels = np.array(image.pixels[:]).reshape(-1, 4)[:, :3]
    Path(out).write_text(json.dumps(pixels.mean(axis=0).tolist()))


if __name__ == "__main__":
    main()
