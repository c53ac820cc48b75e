"""Run by the Blender venv's Python (bpy 4.5): a white furnace in Cycles. A sphere with a clear Principled
transmission skin over a medium that scatters and absorbs nothing, in a uniform white sky, seen head on; prints
the mean radiance inside its outline as JSON (1 where the skin conserves energy). benchmarks/furnace.py runs it.

    python cycles_furnace.py RADIUS ROUGHNESS IOR SIGMA_T DISTRIBUTION SAMPLES
"""

import json
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np

SIZE, FOV, DISTANCE, DEPTH = 64, 20.0, 20.0, 1024  # px, degrees, units of the radius's, bounces


def main() -> None:
    radius, roughness, ior, sigma_t = (float(v) for v in sys.argv[-6:-2])
    distribution, samples = sys.argv[-2], int(sys.argv[-1])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scene.world = world
    bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, segments=128, ring_count=64)
    bpy.ops.object.shade_smooth()
    material = bpy.data.materials.new("skin")
    material.use_nodes = True
    tree = material.node_tree
    skin = tree.nodes["Principled BSDF"]
    skin.distribution = distribution
    skin.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    skin.inputs["Transmission Weight"].default_value = 1.0
    skin.inputs["Roughness"].default_value = roughness
    skin.inputs["IOR"].default_value = ior
    scatter = tree.nodes.new("ShaderNodeVolumeScatter")
    scatter.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scatter.inputs["Density"].default_value = sigma_t
    tree.links.new(scatter.outputs["Volume"], tree.nodes["Material Output"].inputs["Volume"])
    bpy.context.object.data.materials.append(material)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.angle = np.radians(FOV)
    camera.location = (0.0, 0.0, DISTANCE)
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.blur_glossy = 0.0
    for bounces in ("max_bounces", "transmission_bounces", "volume_bounces", "diffuse_bounces", "glossy_bounces"):
        setattr(scene.cycles, bounces, DEPTH)
    scene.view_settings.view_transform = "Standard"
    scene.render.resolution_x = scene.render.resolution_y = SIZE
    scene.render.image_settings.file_format = "OPEN_EXR"
    with tempfile.TemporaryDirectory() as folder:
        scene.render.filepath = str(Path(folder) / "furnace.exr")
        bpy.ops.render.render(write_still=True)
        pixels = np.array(bpy.data.images.load(scene.render.filepath).pixels[:]).reshape(SIZE, SIZE, 4)[..., :3]
    y, x = np.mgrid[:SIZE, :SIZE] - (SIZE - 1) / 2
    outline = radius / (np.tan(np.radians(FOV / 2)) * DISTANCE) * SIZE / 2
    print("FURNACE " + json.dumps({"mean": round(float(pixels[np.hypot(x, y) < 0.95 * outline].mean()), 4)}))


if __name__ == "__main__":
    main()
