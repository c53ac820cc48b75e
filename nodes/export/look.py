"""The whole principled look of a material as flat name → value pairs, carried by both exported files.

UsdPreviewSurface and glTF's extensions each say part of what the preview renders; these attributes say all of
it, under one name each, so that one reader (the Blender add-on in ``blender/nodegraph_import``) sets the same
Principled BSDF from either file: on the USD Material prim as ``nodegraph:principled:<name>``, in the glTF
material's ``extras`` under the same key. Colours are tuples of linear RGB; the subsurface radius is in mm, the
unit of the meshes.
"""

from __future__ import annotations

from ..values import Material

PREFIX = "nodegraph:principled:"


def principled_attributes(material: Material, translucency: float) -> dict[str, float | tuple[float, ...]]:
    """The material's principled set; ``translucency`` is its diffuse-transmission weight (``subsurface`` times
    the CDRF's translucency at the material's median σ, ``gltf_writer.material_translucency``)."""
    return {
        "ior": float(material.ior),
        "transmission": float(material.transmission),
        "transmissionRoughness": float(material.transmission_roughness),
        "subsurface": float(material.subsurface),
        "subsurfaceColor": tuple(float(c) for c in material.subsurface_color),
        "subsurfaceRadius": tuple(float(c) for c in material.subsurface_radius),
        "diffuseTransmission": float(translucency),
        "sheen": float(material.sheen),
        "sheenTint": float(material.sheen_tint),
        "specular": float(material.specular),
    }
