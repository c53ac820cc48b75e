"""The export node — SPEC §4 outputs checked by the ecosystem's validators (Khronos glTF-Validator,
USD's validation framework that ``usdchecker`` runs), plus PLY/OBJ round trips and bad input."""

import io
import json
import struct

import numpy as np
import pytest

from nodegraph.context import Context
from nodes.export import export
from nodes.export.usd_writer import prim_names


def _files(scene, formats, **params):
    return export.call(scene=scene, formats=formats, basename="don", **params).files


def _gltf_json(data: bytes) -> dict:
    length = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20 : 20 + length])


def test_glb_is_valid_with_khr_material_extensions(shaded, gltf_validator):
    data = _files(shaded, ["glb"])["don.glb"]
    report = gltf_validator(data)
    assert report["numErrors"] == 0, report["messages"][:5]
    assert report["numWarnings"] == 0, report["messages"][:5]
    doc = _gltf_json(data)
    assert {
        "KHR_materials_transmission",
        "KHR_materials_volume",
        "KHR_materials_ior",
        "KHR_materials_clearcoat",
        "KHR_materials_sheen",
        "KHR_materials_diffuse_transmission",
    } <= set(doc["extensionsUsed"])
    assert len(doc["nodes"]) - 1 == len(shaded.meshes) and len(doc["meshes"]) < len(shaded.meshes)  # instanced
    primitives = [m["primitives"][0] for m in doc["meshes"]]
    assert all("_CDRF_SIGMA" in p["attributes"] for p in primitives)  # σ travels; baked light does not
    names = [m.name for m in shaded.materials]
    skins = [p for p in primitives if names[p["material"]].startswith("ikura_membrane")]
    assert skins and all("COLOR_0" in p["attributes"] for p in skins)  # each egg's own transmittance, its eye
    assert all("COLOR_0" not in p["attributes"] for p in primitives if p not in skins)
    materials = {m["name"]: m["extensions"] for m in doc["materials"]}
    tint = next(m.name for m in shaded.materials if m.name.startswith("ikura_membrane"))  # one egg's tint
    membrane = materials[tint]
    assert membrane["KHR_materials_ior"]["ior"] == pytest.approx(1.36)
    assert membrane["KHR_materials_transmission"]["transmissionFactor"] == 1.0  # the yolk shows through
    egg = next(m for m in doc["materials"] if m["name"] == tint)
    red, green, blue, _ = egg["pbrMetallicRoughness"]["baseColorFactor"]
    assert red > green > blue  # an orange-red egg
    index = names.index(tint)
    own = np.concatenate([shaded.transmittance[k] for k in np.flatnonzero(shaded.material_of == index)])
    # base colour × COLOR_0 is what light keeps in and out at each vertex (Cycles applies √ at each crossing, as
    # the preview's skin does): the base colour the palest, the eye's, and no vertex's COLOR_0 above 1
    assert [red, green, blue] == pytest.approx(own.max(axis=0), rel=1e-5)
    skin = next(p for p in skins if p["material"] == index)
    accessor = doc["accessors"][skin["attributes"]["COLOR_0"]]
    assert accessor["type"] == "VEC3" and accessor["componentType"] == 5126
    # one reflecting skin, as the preview's: the coat, with no specular of the transmissive base under it
    assert membrane["KHR_materials_specular"]["specularFactor"] == 0.0 and "KHR_materials_clearcoat" in membrane
    assert egg["extras"]["nodegraph:principled:coatIor"] == pytest.approx(1.36)
    assert "attenuationDistance" not in membrane["KHR_materials_volume"]  # no second colouring on the way
    assert doc["materials"][0]["extras"]["nodegraph:principled:subsurface"] > 0  # the whole look, for Blender
    rice = materials["rice"]
    assert 0.05 < rice["KHR_materials_diffuse_transmission"]["diffuseTransmissionFactor"] < 1.0
    assert rice["KHR_materials_sheen"]["sheenColorFactor"][0] > 0 and "KHR_materials_clearcoat" in rice
    assert "KHR_materials_clearcoat" in materials["ceramic"]  # the glaze


def test_validator_catches_a_broken_glb(shaded, gltf_validator):
    data = bytearray(_files(shaded, ["glb"])["don.glb"])
    doc = _gltf_json(bytes(data))
    doc["accessors"][0]["count"] += 10_000  # past the end of its buffer view
    text = json.dumps(doc).encode()
    text += b" " * ((-len(text)) % 4)
    old = struct.unpack_from("<I", data, 12)[0]
    broken = bytes(data[:12]) + struct.pack("<I4s", len(text), b"JSON") + text + bytes(data[20 + old :])
    broken = broken[:8] + struct.pack("<I", len(broken)) + broken[12:]
    assert gltf_validator(broken)["numErrors"] > 0


def _usd_errors(stage):
    """USD's validation errors of ``stage``. usd-core is built without the MaterialX plug-in, so its shader
    registry does not know MaterialX node definitions: a shader whose id MaterialX's own library declares
    (``_materialx_library``) is taken as known, the rest of its checks stand (its inputs are checked against the
    definition in ``test_materialx_standard_surface_beside_the_preview_surface``)."""
    from pxr import UsdValidation

    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    errors = list(UsdValidation.ValidationContext(validators).Validate(stage))
    known = _materialx_library()
    return [
        e
        for e in errors
        if not (
            e.GetName() == "MissingShaderIdInRegistry"
            and any(known.getNodeDef(word.strip("'")) is not None for word in e.GetMessage().split())
        )
    ]


def _materialx_library():
    """MaterialX's standard library of node definitions."""
    mx = pytest.importorskip("MaterialX", reason="MaterialX (pip install materialx) checks the MaterialX shaders")
    library = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), library)
    return library


@pytest.mark.parametrize("fmt", ["usda", "usdc"])
def test_usd_passes_usd_validation(shaded, tmp_path, fmt):
    from pxr import Usd, UsdGeom, UsdShade

    instanced = tmp_path / f"instanced.{fmt}"
    instanced.write_bytes(_files(shaded, [fmt])[f"don.{fmt}"])
    assert _usd_errors(Usd.Stage.Open(str(instanced))) == []
    path = tmp_path / f"don.{fmt}"
    path.write_bytes(_files(shaded, [fmt], instancing=False)[f"don.{fmt}"])
    stage = Usd.Stage.Open(str(path))
    assert _usd_errors(stage) == []
    assert UsdGeom.GetStageUpAxis(stage) == "Z" and UsdGeom.GetStageMetersPerUnit(stage) == pytest.approx(1e-3)
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert len(meshes) == len(shaded.meshes)
    bound = UsdShade.MaterialBindingAPI(meshes[0]).ComputeBoundMaterial()[0]
    assert bound.GetPrim().GetName() == "rice"  # the material's own name: importers show it as it is
    looks = [p.GetName() for p in stage.GetPrimAtPath("/Scene/Looks").GetChildren()]
    assert looks == [m.name for m in shaded.materials]
    assert [p.GetName() for p in meshes] == prim_names([m.name for m in shaded.meshes], "mesh")
    assert 0.05 < bound.GetPrim().GetAttribute("nodegraph:principled:diffuseTransmission").Get() < 1.0
    sigma = UsdGeom.PrimvarsAPI(meshes[0]).GetPrimvar("cdrf_sigma").Get()
    assert len(sigma) == len(shaded.meshes[0].vertices)


def test_prim_names_are_valid_unique_and_keep_the_names():
    assert prim_names(["rice", "ikura/0003/yolk", "", "3d", "rice", "rice_2"], "mesh") == [
        "rice",
        "ikura_0003_yolk",
        "mesh",
        "_3d",
        "rice_2",
        "rice_2_2",
    ]


def test_transmissive_materials_are_translucent_with_their_ior_in_usd(shaded):
    """UsdPreviewSurface: opacity 1 − transmission with the ior (what renderers translate to refraction)."""
    from pxr import UsdShade

    tint = next(m.name for m in shaded.materials if m.name.startswith("ikura_membrane"))  # one egg's tint
    path = f"/Scene/Looks/{tint}/PreviewSurface"
    stage = _stage(shaded)
    shader = UsdShade.Shader(stage.GetPrimAtPath(path))
    assert shader.GetInput("opacity").Get() == pytest.approx(0.0)
    assert shader.GetInput("ior").Get() == pytest.approx(1.36)
    look = stage.GetPrimAtPath("/Scene/Looks/rice")
    rice = next(m for m in shaded.materials if m.name == "rice")
    assert look.GetAttribute("nodegraph:principled:subsurface").Get() == pytest.approx(rice.subsurface)
    assert tuple(look.GetAttribute("nodegraph:principled:subsurfaceRadius").Get()) == pytest.approx(
        rice.subsurface_radius
    )


def test_materialx_standard_surface_beside_the_preview_surface(shaded):
    """Each material also has a MaterialX ``standard_surface`` on its ``mtlx`` output (what Houdini, usdview with
    MaterialX and Omniverse render), carrying the transmission, absorption and subsurface UsdPreviewSurface cannot;
    every input is one the MaterialX node definition declares, with its type."""
    from pxr import UsdShade

    stage = _stage(shaded)
    for material in shaded.materials:
        look = UsdShade.Material(stage.GetPrimAtPath(f"/Scene/Looks/{material.name}"))
        source = look.GetSurfaceOutput("mtlx").GetConnectedSources()[0][0]
        shader = UsdShade.Shader(source.source.GetPrim())
        assert shader.GetIdAttr().Get() == "ND_standard_surface_surfaceshader" and source.sourceName == "out"
        universal = look.GetSurfaceOutput().GetConnectedSources()[0][0].source.GetPrim()
        assert UsdShade.Shader(universal).GetIdAttr().Get() == "UsdPreviewSurface"  # still there for the rest
        values = {i.GetBaseName(): i.Get() for i in shader.GetInputs()}
        assert values["transmission"] == pytest.approx(material.transmission)
        assert values["specular_IOR"] == pytest.approx(material.ior)
        assert values["subsurface"] == pytest.approx(material.subsurface)
        assert tuple(values["subsurface_radius"]) == pytest.approx(material.subsurface_radius)
        assert tuple(values["base_color"]) == pytest.approx(material.base_color)
    tint = next(m.name for m in shaded.materials if m.name.startswith("ikura_membrane"))  # one egg's tint
    membrane = UsdShade.Shader(stage.GetPrimAtPath(f"/Scene/Looks/{tint}/StandardSurface"))
    assert membrane.GetInput("transmission").Get() == pytest.approx(1.0)
    red, green, blue = membrane.GetInput("transmission_color").Get()
    assert red > green > blue  # an orange egg, tinted at each crossing as the glTF's base colour says
    assert membrane.GetInput("transmission_depth").Get() == 0.0
    assert membrane.GetInput("specular").Get() == 0.0 and membrane.GetInput("coat_IOR").Get() == pytest.approx(1.36)
    assert UsdShade.Shader(stage.GetPrimAtPath("/Scene/Looks/rice/StandardSurface")).GetInput("subsurface").Get() > 0
    _matches_node_definition(shader)


def _matches_node_definition(shader):
    """Every input of ``shader`` is declared by its MaterialX node definition with the same type."""
    library = _materialx_library()  # kept: its elements refer to it
    definition = library.getNodeDef(shader.GetIdAttr().Get())
    assert definition is not None
    declared = {i.getName(): i.getType() for i in definition.getActiveInputs()}
    usd_types = {"color3": "color3f", "float": "float", "boolean": "bool", "vector3": "float3"}
    for field in shader.GetInputs():
        assert field.GetBaseName() in declared, f"standard_surface has no input {field.GetBaseName()}"
        assert str(field.GetTypeName()) == usd_types[declared[field.GetBaseName()]], field.GetBaseName()
    assert [o.getType() for o in definition.getActiveOutputs()] == ["surfaceshader"]


def _stage(scene):
    from pxr import Sdf, Usd

    layer = Sdf.Layer.CreateAnonymous(".usda")
    layer.ImportFromString(_files(scene, ["usda"])["don.usda"].decode())
    return Usd.Stage.Open(layer)


def test_usd_validation_is_not_vacuous():
    from pxr import Usd, UsdGeom, UsdShade

    stage = Usd.Stage.CreateInMemory()  # no up axis / meters per unit / default prim, binding without the API
    mesh = UsdGeom.Mesh.Define(stage, "/m")
    look = UsdShade.Material.Define(stage, "/look")
    mesh.GetPrim().CreateRelationship("material:binding").SetTargets([look.GetPath()])
    assert _usd_errors(stage)


def test_ply_and_obj_round_trip_with_srgb_colours(shaded):
    import trimesh

    files = _files(shaded, ["ply", "obj"])
    n = sum(len(m.vertices) for m in shaded.meshes)
    ply = trimesh.load(io.BytesIO(files["don.ply"]), file_type="ply", process=False)
    obj = trimesh.load(io.BytesIO(files["don.obj"]), file_type="obj", process=False)
    assert len(ply.vertices) == n and len(obj.vertices) == n
    assert np.allclose(ply.vertices[: len(shaded.meshes[0].vertices)], shaded.meshes[0].vertices, atol=1e-5)
    from nodes.export.mesh_files import linear_to_srgb8

    assert np.array_equal(
        ply.visual.vertex_colors[: len(shaded.meshes[0].vertices), :3], linear_to_srgb8(shaded.meshes[0].colors)
    )


def test_export_is_deterministic(shaded):
    a, b = _files(shaded, ["glb", "usda", "ply"]), _files(shaded, ["glb", "usda", "ply"])
    assert a == b


@pytest.mark.parametrize(
    "params, match",
    [
        ({"basename": "../escape"}, "plain file name"),
        ({"formats": ["fbx"]}, "unknown format"),
        ({"formats": []}, "at least one"),
    ],
)
def test_bad_export_parameters(shaded, params, match):
    with pytest.raises(ValueError, match=match):
        export(Context.standalone(seed=0), scene=shaded, **{**export.resolve_params({}), **params})
    assert export.check({**export.resolve_params({}), **params})  # refused when the recipe loads, too


def test_unwritable_destination_leaves_nothing_half_written(shaded, tmp_path):
    from nodegraph.output_files import write_output

    fileset = export.call(scene=shaded, formats=["glb", "ply"])
    blocker = tmp_path / "outputs"
    blocker.write_text("a file where the output folder should be")  # fails even for root
    with pytest.raises(OSError):
        write_output(fileset, blocker / "ikura_don", "export")
    assert [p.name for p in tmp_path.rglob("*")] == ["outputs"]
    assert blocker.read_text().startswith("a file")


def test_the_blender_addon_reads_the_keys_the_exporter_writes(shaded):
    """blender/nodegraph_import runs inside Blender only; its keys are checked here against nodes/export/look.py."""
    import ast
    import re
    from pathlib import Path

    from nodes.export.look import PREFIX, principled_attributes
    from nodes.shading.materials import ice_materials

    source = (Path(__file__).resolve().parents[2] / "blender" / "nodegraph_import" / "__init__.py").read_text()
    ast.parse(source)
    assert f'PREFIX = "{PREFIX}"' in source
    read = set(re.findall(r'look(?:\.get\(|\[)"(\w+)"', source))
    written = set().union(*(principled_attributes(m, 0.0) for m in (*shaded.materials, *ice_materials((1, 0, 0)))))
    assert read and read <= written and {"mediumSigmaT", "mediumAlbedo"} <= read, read


def test_the_exported_files_are_not_cached():
    """Issue 47: a shared 2 GiB cache filled within 20 minutes; the export's files were the largest entry of a run
    (the full main job's 78.7 MB of 127.6), made in 1.47 s against 3.8 s to store and 1.3 s to load. The output
    folder keeps them; the cache does not."""
    from nodegraph.registry import default_registry

    assert default_registry().get("export").store is False
