"""Run by the Blender venv's Python (bpy 4.5): import one exported file with the repository's add-on enabled,
report what Blender made as JSON, and render a tiny Cycles image — tests/export/test_blender_roundtrip.py.

    python blender_roundtrip.py SCENE.glb|SCENE.usdc REPORT.json RENDER.png|-     (-: no render)

``tools/blender_import_table.py`` runs it on a recipe's files for the import table (objects, materials,
transmission, seconds).
"""

import json
import os
import sys
import time
from pathlib import Path

import bpy

REPO = Path(__file__).resolve().parents[2]


def enable_addon() -> None:
    import addon_utils

    sys.path.insert(0, str(REPO / "blender"))
    addon_utils.enable("nodegraph_import", default_set=True, handle_error=None)
    if "nodegraph_import" not in bpy.context.preferences.addons:
        raise SystemExit("the nodegraph_import add-on did not enable")


def import_file(path: Path) -> float:
    start = time.perf_counter()
    if path.suffix == ".glb":
        bpy.ops.import_scene.gltf(filepath=str(path))  # the add-on's glTF user extension runs inside
    else:
        bpy.ops.wm.usd_import(filepath=str(path))
        if "nodegraph_import" in bpy.context.preferences.addons:
            # the add-on's USDHook needs Blender's bundled pxr, which the bpy wheel lacks: its function, called here
            bpy.ops.nodegraph.apply_looks()
    return time.perf_counter() - start


def base_factor(bsdf):
    """The base colour, or where the importer multiplies a vertex colour into it (glTF ``COLOR_0``), its factor:
    the 'Color Factor' mix node's second colour."""
    socket = bsdf.inputs["Base Color"]
    if not socket.is_linked:
        return socket.default_value
    node = socket.links[0].from_node
    return node.inputs[7].default_value if node.type == "MIX" else socket.default_value


def material_report(material) -> dict:
    bsdf = (
        next((n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None) if material.use_nodes else None
    )
    if bsdf is None:
        return {}
    value = lambda name: bsdf.inputs[name].default_value
    output = next(n for n in material.node_tree.nodes if n.type == "OUTPUT_MATERIAL")
    return {
        "transmission": value("Transmission Weight"),
        "ior": value("IOR"),
        "alpha": value("Alpha"),
        "subsurface": value("Subsurface Weight"),
        "subsurface_radius": list(value("Subsurface Radius")),
        "subsurface_scale": value("Subsurface Scale"),
        "volume": output.inputs["Volume"].is_linked,
        "base_color": list(base_factor(bsdf))[:3],
        "vertex_color": any(n.type == "VERTEX_COLOR" for n in material.node_tree.nodes),
        "scatters": any(n.type == "VOLUME_SCATTER" for n in material.node_tree.nodes),
        "specular_level": value("Specular IOR Level"),
        "coat_ior": value("Coat IOR"),
        "coat_weight": value("Coat Weight"),
        "roughness": value("Roughness"),
    }


def drawn_meshes() -> list[int]:
    """The vertex count of each mesh Blender draws: objects and the instances of the USD point instancers'
    geometry nodes alike (the evaluated scene's object instances)."""
    bpy.context.view_layer.update()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    return [len(i.object.data.vertices) for i in depsgraph.object_instances if i.object.type == "MESH"]


def render(path: Path) -> float:
    """A 64 × 36 Cycles render (CPU, 8 samples) from above at a slant, lit by a sun only (a black world, so only
    lit objects are not black); its mean pixel value in [0, 1]."""
    import numpy as np
    from mathutils import Vector

    scene = bpy.context.scene
    depsgraph = bpy.context.evaluated_depsgraph_get()  # world matrices of the imported objects and instances
    # an instance's object is valid only during the iteration (Blender's ``Depsgraph.object_instances``): read its
    # box there; a box read afterwards came from freed memory, and one run in about six framed a black nothing
    corners = [
        i.matrix_world @ Vector(c)
        for i in depsgraph.object_instances
        if i.object.type == "MESH"
        for c in i.object.bound_box
    ]
    low = Vector([min(c[i] for c in corners) for i in range(3)])
    high = Vector([max(c[i] for c in corners) for i in range(3)])
    centre, size = (low + high) / 2, max((high - low).length, 1e-3)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.data.clip_start, camera.data.clip_end = size * 1e-2, size * 1e2  # a dish is centimetres across
    camera.location = centre + Vector((0.0, -1.0, 1.2)) * size
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", type="SUN"))
    sun.data.energy = 3.0
    scene.collection.objects.link(sun)
    scene.world = bpy.data.worlds.new("black")  # no sky light: only lit objects are not black
    scene.world.color = (0.0, 0.0, 0.0)
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 8
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 36, 100
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(str(path))
    pixels = np.array(image.pixels[:]).reshape(-1, 4)[:, :3]
    return float(pixels.mean())


def main() -> None:
    source, report_path, render_path = (Path(a) for a in sys.argv[-3:])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon = os.environ.get("NODEGRAPH_BLENDER_ADDON", "1") != "0"  # 0: Blender's importers alone
    if addon:
        enable_addon()
    seconds = import_file(source)
    drawn = drawn_meshes()
    report = {
        "seconds": seconds,
        "objects": len(bpy.data.objects),
        "meshes": len(drawn),
        "vertices": sum(drawn),
        "mesh_data": len(bpy.data.meshes),  # fewer than meshes where instances share one
        "materials": {m.name: material_report(m) for m in bpy.data.materials if m.users},
    }
    if str(render_path) != "-":
        report["render_mean"] = render(render_path)
    report_path.write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
