"""Run by the Blender venv's Python (bpy 4.5): render an exported .glb with Cycles under the preview's camera
and light, for a side-by-side with our Mitsuba preview (tools/blender_side_by_side.py writes SETTINGS.json).

    python blender_render_glb.py SCENE.glb SETTINGS.json RENDER.png

The repository's add-on reads the look the exporter wrote (``blender/nodegraph_import``). The camera is fitted
to the drawn meshes by the preview's rule (``fit_camera``: the same numbers as
``nodes.export.mitsuba_scene.look_at``, repeated here since bpy's venv cannot import the project: it pins numpy
1.26); the light is the preview's: a uniform sky, the key as a sun of the same angular size and irradiance, its
glints' core as a small sun seen only in glossy reflections, a matte table under the scene; the same exposure;
Blender's 'Standard' view transform (sRGB, no filmic curve).
"""

import json
import sys
from pathlib import Path

import bpy
import numpy as np
from mathutils import Matrix, Vector

REPO = Path(__file__).resolve().parents[1]


def drawn_points() -> np.ndarray:
    """World-space vertices of every drawn mesh (objects and glTF instances), at most ≈ 100,000."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    chunks = []
    for instance in depsgraph.object_instances:
        if instance.object.type != "MESH":
            continue
        mesh = instance.object.data
        local = np.empty(len(mesh.vertices) * 3)
        mesh.vertices.foreach_get("co", local)
        local = local.reshape(-1, 3)[::8]
        matrix = np.array(instance.matrix_world)
        chunks.append(local @ matrix[:3, :3].T + matrix[:3, 3])
    points = np.concatenate(chunks)
    return points[:: max(1, len(points) // 100_000)]


def fit_camera(points: np.ndarray, elevation, azimuth, fov, margin, aspect):
    """(origin, target): the subject centred and as large as leaves ``margin`` of the half-frame free on its
    tightest side (``nodes.export.mitsuba_scene.look_at``)."""
    el, az = np.radians(elevation), np.radians(azimuth)
    view = np.array([np.sin(az) * np.cos(el), -np.cos(az) * np.cos(el), np.sin(el)])
    right = np.cross(-view, [0.0, 0.0, 1.0])
    right = right / np.linalg.norm(right) if np.linalg.norm(right) > 1e-9 else np.array([1.0, 0.0, 0.0])
    up = np.cross(right, -view)
    free, tan_x = 1.0 - margin, np.tan(np.radians(fov) / 2)
    tan_y = tan_x / aspect
    target = 0.5 * (points.min(axis=0) + points.max(axis=0))

    def distance_to(target):
        rel = points - target
        x, y, z = rel @ right, rel @ up, rel @ view
        distance = float(np.max(z + np.maximum(np.abs(x) / (free * tan_x), np.abs(y) / (free * tan_y))))
        return max(distance, float(z.max()) + 1e-6 * float(np.ptp(points, axis=0).max() + 1.0)), x, y, z

    for _ in range(4):
        distance, x, y, z = distance_to(target)
        u, v = x / ((distance - z) * tan_x), y / ((distance - z) * tan_y)
        target = target + distance * (
            0.5 * (u.max() + u.min()) * tan_x * right + 0.5 * (v.max() + v.min()) * tan_y * up
        )
    distance = distance_to(target)[0]
    return target + distance * view, target


def sun(name, direction, strength, angle, diffuse=True):
    light = bpy.data.lights.new(name, type="SUN")
    light.energy, light.angle = strength, angle
    obj = bpy.data.objects.new(name, light)
    obj.rotation_euler = Vector(direction).to_track_quat("Z", "Y").to_euler()  # a sun shines along its −Z
    obj.visible_diffuse = diffuse
    obj.visible_transmission = diffuse
    obj.visible_volume_scatter = diffuse
    bpy.context.scene.collection.objects.link(obj)
    return obj


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
    points = drawn_points()
    origin, target = fit_camera(points, s["elevation"], s["azimuth"], s["fov"], s["margin"], s["width"] / s["height"])
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    size = float(np.ptp(points, axis=0).max())
    camera.data.sensor_fit = "HORIZONTAL"
    camera.data.angle = np.radians(s["fov"])
    camera.data.clip_start, camera.data.clip_end = size * 1e-3, size * 1e3
    camera.matrix_world = Matrix.Translation(Vector(origin)) @ (
        Vector(target - origin).to_track_quat("-Z", "Z").to_matrix().to_4x4()
    )
    scene.collection.objects.link(camera)
    scene.camera = camera

    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = s["sky"]
    scene.world = world
    direction = np.asarray(s["sun_direction"], float) / np.linalg.norm(s["sun_direction"])
    sun("key", direction, s["key_irradiance"], 2 * s["key_angle"])
    sun("glints", direction, s["glint_irradiance"], 2 * s["glint_angle"], diffuse=False)
    bpy.ops.mesh.primitive_plane_add(size=40 * size, location=(target[0], target[1], points[:, 2].min() - 1e-3 * size))
    table = bpy.context.active_object
    material = bpy.data.materials.new("table")
    material.use_nodes = True
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*s["table_color"], 1.0)
    material.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 1.0
    material.node_tree.nodes["Principled BSDF"].inputs["Specular IOR Level"].default_value = 0.0
    table.data.materials.append(material)

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = s["samples"]
    scene.cycles.seed = 0
    scene.cycles.max_bounces = s["max_depth"]
    scene.cycles.transmission_bounces = s["max_depth"]
    scene.cycles.volume_bounces = s["max_depth"]
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
