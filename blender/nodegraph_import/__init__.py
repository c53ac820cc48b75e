"""nodegraph import: the whole nodegraph look in Blender, from the .glb and the .usdc.

Blender's own importers carry most of a nodegraph material (colour, roughness, coat; the glTF importer also
transmission, IOR, volume and sheen) but not all of it: the USD importer reads UsdPreviewSurface's ``opacity``
as alpha, so eggs and ice come back as see-through ghosts that do not refract, and neither importer knows
subsurface scattering, so rice renders as plaster. nodegraph writes each material's whole principled set beside
what the importers read: as ``nodegraph:principled:*`` attributes on the USD Material prim and under the same
keys in the glTF material's ``extras``. Both importers keep those as the material's custom properties; this
add-on sets the Principled BSDF from them:

- the light under the skin the preview renders: where the files carry a medium (``mediumSigmaT``,
  ``mediumAlbedo``: rice grains, ikura yolks, ice flakes) a clear skin of the preview's roughness (none where the
  files say ``boundaryIor`` 1: ice; where they give a ``filmIor``, rice, a coat at that IOR and the skin's
  roughness over the unbent boundary: the wet film) over a volume
  that scatters and absorbs as the preview's medium (Cycles renders it; set enough volume bounces);
- transmission and IOR (alpha back to 1; an element inside another, the yolk in the egg's fluid, gets its IOR
  relative to it, ``exteriorIor``: Cycles has no stack of IORs); the colour light keeps through the element is
  the base colour both files carry (Cycles tints each crossing by its square root); where the coat is the
  element's only reflecting skin (``coatIor``: the ikura membrane) no coat, and the transmission lobe at the
  element's IOR and transmission roughness is that one skin: Cycles' transmission lobe reflects by Fresnel at
  the IOR whatever the Specular IOR Level (which scales only the opaque specular layer), so with the coat on
  the membrane reflected twice (a slab of it under a white sky: 0.050 in green against Fresnel's 0.025;
  docs/look.md, "Side by side with Blender");
- otherwise subsurface weight and radius (radius in mm, the files' unit: Subsurface Scale 0.001, Blender's metres after
  both importers' default unit conversion);
- sheen and specular level where the importer did not map them.

It runs by itself after File > Import > glTF 2.0 (a glTF importer user extension) and after File > Import >
Universal Scene Description (a ``bpy.types.USDHook``). For files imported before the add-on was enabled, or from
a script, run "Apply nodegraph Looks" (F3 search) or call ``apply_looks()``.
"""

from __future__ import annotations

import bpy

bl_info = {
    "name": "nodegraph import",
    "author": "nodegraph",
    "version": (1, 0, 0),
    "blender": (4, 2, 0),
    "location": "File > Import > glTF 2.0 / Universal Scene Description",
    "description": "Transmission, IOR and subsurface scattering of nodegraph's .glb and .usd files",
    "category": "Import-Export",
}

PREFIX = "nodegraph:principled:"
MM = 1e-3  # metres per millimetre: the files' unit after the importers' unit conversion
SHEEN_ROUGHNESS = 0.5  # the exporter's glTF sheen roughness (nodes/export/gltf_writer.py)


def look_of(material) -> dict:
    """The ``nodegraph:principled:*`` custom properties of a material, by short name (arrays as tuples)."""
    out = {}
    for key in material.keys():
        if key.startswith(PREFIX):
            value = material[key]
            out[key[len(PREFIX) :]] = tuple(value) if hasattr(value, "__len__") else float(value)
    return out


def _principled(material):
    """The Principled BSDF that feeds the material output's surface (None if there is none)."""
    if not material.use_nodes or material.node_tree is None:
        return None
    for node in material.node_tree.nodes:
        if node.type == "OUTPUT_MATERIAL" and node.inputs["Surface"].is_linked:
            source = node.inputs["Surface"].links[0].from_node
            if source.type == "BSDF_PRINCIPLED":
                return source
    return next((n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)


def _set_medium(material, look: dict) -> None:
    """The preview's medium inside the element (``mediumSigmaT`` mm⁻¹, ``mediumAlbedo``): a volume scatter of
    σs = albedo × σt and an absorption of σa = (1 − albedo) × σt (Cycles: density × (1 − colour)), isotropic, in
    place of any volume the importer made (the glTF importer makes an absorption from KHR_materials_volume)."""
    tree = material.node_tree
    output = next((n for n in tree.nodes if n.type == "OUTPUT_MATERIAL"), None)
    if output is None:
        return
    for link in list(output.inputs["Volume"].links):
        tree.links.remove(link)
    density = look["mediumSigmaT"] / MM  # per metre: Blender's scene unit
    albedo = (*look["mediumAlbedo"], 1.0)
    scatter = tree.nodes.new("ShaderNodeVolumeScatter")
    absorb = tree.nodes.new("ShaderNodeVolumeAbsorption")
    both = tree.nodes.new("ShaderNodeAddShader")
    for node, dy in ((scatter, -250), (absorb, -450), (both, -350)):
        node.location = (output.location.x - (400 if node is not both else 200), output.location.y + dy)
    scatter.inputs["Color"].default_value = albedo
    scatter.inputs["Density"].default_value = density
    scatter.inputs["Anisotropy"].default_value = 0.0
    absorb.inputs["Color"].default_value = albedo
    absorb.inputs["Density"].default_value = density
    tree.links.new(scatter.outputs["Volume"], both.inputs[0])
    tree.links.new(absorb.outputs["Volume"], both.inputs[1])
    tree.links.new(both.outputs["Shader"], output.inputs["Volume"])


def apply_look(material) -> bool:
    """Set the material's Principled BSDF from its nodegraph look; False when it carries none."""
    look = look_of(material)
    bsdf = _principled(material)
    if not look or bsdf is None:
        return False
    inputs = bsdf.inputs
    if "ior" in look:  # Cycles has no stack of IORs: an element inside another gets its IOR relative to it
        inputs["IOR"].default_value = look["ior"] / look.get("exteriorIor", 1.0)
    transmission = look.get("transmission", 0.0)
    if "mediumSigmaT" in look:  # the preview's light under the skin: a clear skin over a scattering medium
        inputs["Transmission Weight"].default_value = 1.0
        inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        inputs["Roughness"].default_value = look["boundaryRoughness"]
        if "boundaryIor" in look:  # no skin (shaved ice) or a film (rice): an index-matched boundary, not bending
            inputs["IOR"].default_value = look["boundaryIor"]
            inputs["Roughness"].default_value = 0.0
        inputs["Subsurface Weight"].default_value = 0.0
        inputs["Coat Weight"].default_value = 0.0
        if "filmIor" in look:  # rice's wet film: the coat reflects Fresnel's share at its roughness, as the preview's
            inputs["Coat Weight"].default_value = 1.0  # film pass; the rest passes unbent into the medium
            inputs["Coat IOR"].default_value = look["filmIor"]
            inputs["Coat Roughness"].default_value = look["boundaryRoughness"]
            inputs["Coat Tint"].default_value = (1.0, 1.0, 1.0, 1.0)
        inputs["Alpha"].default_value = 1.0
        material.surface_render_method = "DITHERED"
        _set_medium(material, look)
    elif transmission > 0:  # the colour light keeps through the element is the base colour both files carry
        inputs["Transmission Weight"].default_value = transmission
        inputs["Alpha"].default_value = 1.0  # the USD importer's reading of opacity = 1 − transmission
        material.surface_render_method = "DITHERED"
        if "coatIor" in look:  # one reflecting skin: the glass lobe's, as the preview's one dielectric
            inputs["Coat Weight"].default_value = 0.0
            inputs["Roughness"].default_value = look["transmissionRoughness"]
    elif look.get("subsurface", 0.0) > 0:
        inputs["Subsurface Weight"].default_value = look["subsurface"]
        inputs["Subsurface Radius"].default_value = look["subsurfaceRadius"]
        inputs["Subsurface Scale"].default_value = MM
    if "mediumSigmaT" in look:  # the preview's skin over a medium is a plain dielectric
        inputs["Sheen Weight"].default_value = 0.0
        return True
    if look.get("sheen", 0.0) > 0 and not inputs["Sheen Weight"].is_linked:
        tint, base = look.get("sheenTint", 0.5), inputs["Base Color"].default_value
        inputs["Sheen Weight"].default_value = look["sheen"]
        inputs["Sheen Tint"].default_value = (*((1 - tint) + tint * base[c] for c in range(3)), 1.0)
        inputs["Sheen Roughness"].default_value = SHEEN_ROUGHNESS
    if "specular" in look:
        inputs["Specular IOR Level"].default_value = look["specular"]
    return True


def apply_looks(materials=None) -> int:
    """Apply every nodegraph look (all materials by default); how many materials carried one."""
    return sum(apply_look(m) for m in (bpy.data.materials if materials is None else materials))


class glTF2ImportUserExtension:
    """Blender's glTF importer calls this for each material it makes (the add-on must be enabled)."""

    def gather_import_material_after_hook(self, gltf_material, vertex_color, blender_material, gltf):
        apply_look(blender_material)


class NODEGRAPH_USDHook(bpy.types.USDHook):
    """After a USD import: apply the looks the imported materials carry as custom properties."""

    bl_idname = "nodegraph_usd_hook"
    bl_label = "nodegraph looks"
    bl_description = "Transmission, IOR and subsurface scattering from nodegraph:principled:* attributes"

    @staticmethod
    def on_import(import_context):
        apply_looks()
        return True


class NODEGRAPH_OT_apply_looks(bpy.types.Operator):
    """Set every material that carries a nodegraph look (transmission, IOR, subsurface) from it"""

    bl_idname = "nodegraph.apply_looks"
    bl_label = "Apply nodegraph Looks"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        count = apply_looks()
        self.report({"INFO"}, f"nodegraph looks applied to {count} material(s)")
        return {"FINISHED"}


def _usd_hooks_can_run() -> bool:
    """Blender calls USD hooks through its bundled USD Python bindings (``pxr``); the ``bpy`` module from the
    package registry has none and aborts on the first hook call, so there the hook is not registered and
    ``apply_looks()`` is called after the import instead."""
    import importlib.util

    return importlib.util.find_spec("pxr") is not None


def _classes():
    return (NODEGRAPH_USDHook, NODEGRAPH_OT_apply_looks) if _usd_hooks_can_run() else (NODEGRAPH_OT_apply_looks,)


def register():
    for cls in _classes():
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(_classes()):
        bpy.utils.unregister_class(cls)
