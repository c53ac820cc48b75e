"""A shaded scene as USD (usd-core): UsdGeom meshes, UsdPreviewSurface and MaterialX materials — SPEC §4 output.

Z-up, millimetres (``metersPerUnit`` 0.001). Per-vertex CDRF colours go to ``primvars:displayColor`` (the
fallback colour of viewers without materials), the CDRF's per-vertex σ to ``primvars:cdrf_sigma`` and a skin's own
per-vertex transmittance, where it has one (an egg's membrane, paler over its eye), to ``primvars:transmittance``;
each material's principled parameters map onto UsdPreviewSurface. Transmission has no input there: a
transmissive material (egg, syrup-soaked ice) gets ``opacity`` = 1 − transmission with its ``ior``, which the
UsdPreviewSurface specification reads as a translucent surface that still reflects (clear glass at 0), and which
renderers that translate it to transmission render as refraction. Blender's importer reads ``opacity`` as
alpha instead; the add-on in ``blender/nodegraph_import`` turns it back into transmission. The full principled
set the preview renders (subsurface weight and radius, sheen, transmission, diffuse transmission) is kept on the
Material prim as ``nodegraph:principled:*`` attributes (Blender's importer keeps them as the material's custom
properties, which the add-on reads). Prim names are the meshes' and materials' own names made valid for USD
(``ikura/0003/yolk`` → ``ikura_0003_yolk``), so importers show them as the recipe names them.
Beside the UsdPreviewSurface (the material's universal ``outputs:surface``) each material has a MaterialX
``standard_surface`` shader on ``outputs:mtlx:surface``, the convention of USD's MaterialX plug-in: renderers that
read MaterialX (Houdini's Karma, usdview's Storm, Omniverse) take it and get transmission with absorption,
subsurface and sheen; the others keep the UsdPreviewSurface. ``standard_surface`` rather than OpenPBR because
MaterialX 1.38, which many of them still ship, has only the former.
``.usda`` comes from the in-memory layer; ``.usdc`` (crate) can only be
written to a path, so it goes through a private temporary directory and is read back as bytes.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np

from ..values import Material, ShadedScene
from .gltf_writer import SHEEN_ROUGHNESS
from .look import PREFIX, coat_is_skin, crossing_tint, exported_base_color, exported_specular, principled_attributes


def load_libraries() -> None:
    """Every USD library the writer opens: the pxr modules it imports and the crate format's plugin, which USD loads
    on first use (the export's ``NodeSpec.libraries``: loaded in the main thread before the export runs beside the
    preview; USD's initialiser drops and retakes the GIL, and a run of the onigiri hung so, the render's thread
    waiting on the loader's lock that USD held in the export's)."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt  # noqa: F401 - loaded for their libraries

    Sdf.FileFormat.FindByExtension("usdc")
    Usd.Stage.CreateInMemory()


def prim_names(texts, fallback: str) -> list[str]:
    """Valid, unique USD prim names from mesh or material names, in order: characters USD does not allow
    become ``_``, a leading digit gets a ``_`` before it, an empty name is ``fallback``; a repeated name gets
    ``_2``, ``_3``, ... (the first keeps its name)."""
    names, taken = [], set()
    for text in texts:
        base = re.sub(r"[^A-Za-z0-9_]", "_", text) or fallback
        if base[0].isdigit():
            base = "_" + base
        name, k = base, 1
        while name in taken:
            k += 1
            name = f"{base}_{k}"
        taken.add(name)
        names.append(name)
    return names


STANDARD_SURFACE = "ND_standard_surface_surfaceshader"  # MaterialX's node definition (stdlib, 1.38 and 1.39)


def standard_surface_inputs(material: Material) -> dict[str, float | tuple[float, float, float]]:
    """The material's principled parameters as MaterialX ``standard_surface`` inputs (name → float or linear RGB).

    Lengths are in the scene's unit (mm): ``subsurface_radius`` is the principled radius with ``subsurface_scale``
    1; a transmissive skin tints light at each crossing (``transmission_color`` = ``look.crossing_tint`` with
    ``transmission_depth`` 0), as the preview renders it and the glTF file's base colour says. Specular follows
    Blender's convention as there: 0.5 is the dielectric default (weight 1)."""
    tint = (1.0 - material.sheen_tint) + material.sheen_tint * np.asarray(material.base_color)

    def rgb(values) -> tuple[float, float, float]:
        return tuple(float(c) for c in values)

    return {
        "base": 1.0,
        "base_color": rgb(material.base_color),
        "metalness": float(material.metallic),
        "specular": float(min(1.0, 2.0 * exported_specular(material))),
        "specular_roughness": float(material.roughness),
        "specular_IOR": float(material.ior),
        "specular_anisotropy": float(material.anisotropic),
        "specular_rotation": float(material.anisotropic_rotation),
        "transmission": float(material.transmission),
        "transmission_color": rgb(crossing_tint(material)),
        "transmission_depth": 0.0,  # the tint applies at each crossing of the skin, as in the preview
        "transmission_extra_roughness": float(material.transmission_roughness),
        "subsurface": float(material.subsurface),
        "subsurface_color": rgb(material.subsurface_color),
        "subsurface_radius": rgb(material.subsurface_radius),
        "subsurface_scale": 1.0,
        "sheen": float(material.sheen),
        "sheen_color": rgb(np.clip(tint, 0.0, 1.0)),
        "sheen_roughness": SHEEN_ROUGHNESS,
        "coat": float(material.clearcoat),
        "coat_roughness": float(material.clearcoat_roughness),
        "coat_IOR": float(material.ior if coat_is_skin(material) else 1.5),
        "emission": float(material.emission_strength if max(material.emission) > 0 else 0.0),
        "emission_color": rgb(material.emission),
    }


def _material(stage, path: str, material: Material, translucency: float):
    from pxr import Gf, Sdf, UsdShade

    look = UsdShade.Material.Define(stage, path)
    shader = UsdShade.Shader.Define(stage, f"{path}/PreviewSurface")
    shader.CreateIdAttr("UsdPreviewSurface")
    inputs = {
        "diffuseColor": (Sdf.ValueTypeNames.Color3f, Gf.Vec3f(*exported_base_color(material))),
        "emissiveColor": (
            Sdf.ValueTypeNames.Color3f,
            Gf.Vec3f(*(np.asarray(material.emission) * material.emission_strength).tolist()),
        ),
        "metallic": (Sdf.ValueTypeNames.Float, material.metallic),
        "roughness": (Sdf.ValueTypeNames.Float, material.roughness),
        "clearcoat": (Sdf.ValueTypeNames.Float, material.clearcoat),
        "clearcoatRoughness": (Sdf.ValueTypeNames.Float, material.clearcoat_roughness),
        "ior": (Sdf.ValueTypeNames.Float, material.ior),
        "opacity": (Sdf.ValueTypeNames.Float, 1.0 - material.transmission),
    }
    for name, (kind, value) in inputs.items():
        shader.CreateInput(name, kind).Set(value)
    look.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    mtlx = UsdShade.Shader.Define(stage, f"{path}/StandardSurface")
    mtlx.CreateIdAttr(STANDARD_SURFACE)
    for name, value in standard_surface_inputs(material).items():
        kind = Sdf.ValueTypeNames.Color3f if isinstance(value, tuple) else Sdf.ValueTypeNames.Float
        mtlx.CreateInput(name, kind).Set(Gf.Vec3f(*value) if isinstance(value, tuple) else value)
    look.CreateSurfaceOutput("mtlx").ConnectToSource(mtlx.CreateOutput("out", Sdf.ValueTypeNames.Token))
    prim = look.GetPrim()
    for name, value in principled_attributes(material, translucency).items():
        kind = Sdf.ValueTypeNames.Color3f if isinstance(value, tuple) else Sdf.ValueTypeNames.Float
        prim.CreateAttribute(PREFIX + name, kind, custom=True).Set(
            Gf.Vec3f(*value) if isinstance(value, tuple) else float(value)
        )
    return look


def build_stage(scene: ShadedScene, instancing: bool = True, groups=None, weights=None):
    """An in-memory stage holding the scene under ``/Scene`` (the default prim). With ``instancing``, each group
    of meshes that are one mesh moved rigidly (``instancing.instance_groups``) is a ``PointInstancer`` of one
    prototype instead of a copy per element. ``groups`` and ``weights``: the scene's ``instance_groups`` and
    ``gltf_writer.material_translucency`` when already found (``gltf_writer.glb_bytes``).

    The elements are authored with the Sdf API in one change block (``_mesh_prim``): the stage recomposes once,
    not once per prim (the UsdGeom API took ≈ 1 ms per mesh, 3 s for 3,000 grains). The specs and their fields
    are the ones ``UsdGeom.Mesh.Define`` and its ``Create*Attr`` would author, in the same order, so the files
    are byte for byte the same."""
    from pxr import Gf, Sdf, Usd, UsdGeom, Vt

    from .instancing import written_meshes

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1e-3)
    root = UsdGeom.Xform.Define(stage, "/Scene")
    stage.SetDefaultPrim(root.GetPrim())
    UsdGeom.Scope.Define(stage, "/Scene/Looks")
    from .gltf_writer import material_translucency

    weights = material_translucency(scene) if weights is None else weights
    looks = [
        _material(stage, f"/Scene/Looks/{name}", m, weights[k]).GetPath()
        for k, (m, name) in enumerate(zip(scene.materials, prim_names([m.name for m in scene.materials], "material")))
    ]
    names = prim_names([mesh.name for mesh in scene.meshes], "mesh")
    out = written_meshes(scene, instancing, groups)
    groups = out.prototypes
    UsdGeom.Scope.Define(stage, "/Scene/Elements")
    layer = stage.GetRootLayer()
    with Sdf.ChangeBlock():
        for k, vertices, low, high in zip(out.indices, out.positions, out.lows, out.highs):
            extent = np.stack([low, high])
            group = groups.get(k)
            if group is None:
                _mesh_prim(layer, f"/Scene/Elements/{names[k]}", scene, k, vertices, extent, looks)
                continue
            path = f"/Scene/Elements/{names[k]}_instances"
            instancer = _prim_spec(layer, path, "PointInstancer")
            _mesh_prim(layer, f"{path}/{names[k]}", scene, k, vertices, extent, looks)
            prototypes = Sdf.RelationshipSpec(instancer, "prototypes", False, Sdf.VariabilityUniform)
            prototypes.targetPathList.explicitItems = [Sdf.Path(f"{path}/{names[k]}")]
            types = Sdf.ValueTypeNames
            _attribute(
                instancer, "protoIndices", types.IntArray, Vt.IntArray.FromNumpy(np.zeros(len(group.members), np.int32))
            )
            _attribute(
                instancer, "positions", types.Point3fArray, Vt.Vec3fArray.FromNumpy(group.positions.astype(np.float32))
            )
            quaternions = group.quaternions()  # (x, y, z, w); USD's quaternions are (w, x, y, z)
            # orientations (half floats: ≈ 1e-3 rad, 1.5 µm at a grain's tip) is what Blender 4.5 reads;
            # orientationsf (float, USD ≥ 24.11) takes precedence where it is known
            halves = [Gf.Quath(float(q[3]), *map(float, q[:3])) for q in quaternions]
            _attribute(instancer, "orientations", types.QuathArray, Vt.QuathArray(halves))
            floats = [Gf.Quatf(float(q[3]), *map(float, q[:3])) for q in quaternions]
            _attribute(instancer, "orientationsf", types.QuatfArray, Vt.QuatfArray(floats))
    return stage


def _prim_spec(layer, path: str, type_name: str):
    """The spec ``UsdGeom.<type_name>.Define`` authors: a defined prim of that type."""
    from pxr import Sdf

    spec = Sdf.CreatePrimInLayer(layer, path)
    spec.specifier = Sdf.SpecifierDef
    spec.typeName = type_name
    return spec


def _attribute(prim, name: str, kind, value, uniform: bool = False, interpolation: str | None = None):
    """The attribute spec ``Create<Name>Attr(value)`` authors (a schema attribute: not custom), then the
    interpolation ``Set<Name>Interpolation`` adds after it."""
    from pxr import Sdf

    attribute = Sdf.AttributeSpec(prim, name, kind, Sdf.VariabilityUniform if uniform else Sdf.VariabilityVarying)
    attribute.default = value
    if interpolation is not None:
        attribute.SetInfo("interpolation", interpolation)


def _primvar(prim, name: str, kind, value):
    """The vertex primvar ``CreatePrimvar(name, kind, vertex).Set(value)`` authors: the interpolation first."""
    from pxr import Sdf, UsdGeom

    attribute = Sdf.AttributeSpec(prim, f"primvars:{name}", kind, Sdf.VariabilityVarying)
    attribute.SetInfo("interpolation", UsdGeom.Tokens.vertex)
    attribute.default = value


def _mesh_prim(layer, path: str, scene: ShadedScene, k: int, points: np.ndarray, extent: np.ndarray, looks) -> None:
    """Scene mesh k as a UsdGeom.Mesh at ``path`` with the given float32 vertex positions and their extent (min
    and max rows), bound to its material (the path of ``looks[material]``): the specs ``UsdGeom.Mesh.Define``,
    ``Create*Attr`` and ``UsdShade.MaterialBindingAPI.Apply(...).Bind`` author, field by field in their order."""
    from pxr import Sdf, UsdGeom, Vt

    mesh = scene.meshes[k]
    types = Sdf.ValueTypeNames
    prim = _prim_spec(layer, path, "Mesh")
    _attribute(prim, "points", types.Point3fArray, Vt.Vec3fArray.FromNumpy(points))
    _attribute(prim, "faceVertexCounts", types.IntArray, Vt.IntArray.FromNumpy(np.full(len(mesh.faces), 3, np.int32)))
    indices = Vt.IntArray.FromNumpy(np.asarray(mesh.faces, np.int32).reshape(-1))
    _attribute(prim, "faceVertexIndices", types.IntArray, indices)
    _attribute(prim, "subdivisionScheme", types.Token, UsdGeom.Tokens.none, uniform=True)
    _attribute(prim, "extent", types.Float3Array, Vt.Vec3fArray.FromNumpy(extent))
    if mesh.normals is not None:
        normals = Vt.Vec3fArray.FromNumpy(np.asarray(mesh.normals, np.float32))
        _attribute(prim, "normals", types.Normal3fArray, normals, interpolation=UsdGeom.Tokens.vertex)
    if mesh.colors is not None:
        _primvar(
            prim,
            "displayColor",
            types.Color3fArray,
            Vt.Vec3fArray.FromNumpy(np.asarray(mesh.colors, np.float32)[:, :3]),
        )
    if scene.cdrf_sigma:
        _primvar(
            prim, "cdrf_sigma", types.FloatArray, Vt.FloatArray.FromNumpy(np.asarray(scene.cdrf_sigma[k], np.float32))
        )
    own = scene.vertex_transmittance(k)
    if own is not None:
        _primvar(prim, "transmittance", types.Float3Array, Vt.Vec3fArray.FromNumpy(np.asarray(own, np.float32)))
    prim.SetInfo("apiSchemas", Sdf.TokenListOp.Create(prependedItems=["MaterialBindingAPI"]))
    binding = Sdf.RelationshipSpec(prim, "material:binding", False, Sdf.VariabilityUniform)
    binding.targetPathList.explicitItems = [looks[scene.material_of[k]]]


def usd_bytes(scene: ShadedScene, binary: bool, instancing: bool = True, groups=None, weights=None) -> bytes:
    """The scene as .usda text or .usdc crate bytes."""
    stage = build_stage(scene, instancing, groups, weights)
    if not binary:
        return stage.GetRootLayer().ExportToString().encode()
    with tempfile.TemporaryDirectory(prefix="nodegraph_usd_") as folder:
        path = Path(folder) / "scene.usdc"
        if not stage.GetRootLayer().Export(str(path)):
            raise ValueError("usd-core could not write the .usdc crate file")
        return path.read_bytes()
