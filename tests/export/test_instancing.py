"""Instancing in the exported files: a mesh that is another mesh moved rigidly is written once and placed per
element (USD PointInstancer, glTF nodes sharing one mesh); a dented copy is written as its own mesh. Each file
read back must give every element's vertices where the scene has them."""

import json
import struct

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from nodegraph.values import Mesh
from nodes.export import export
from nodes.export.instancing import TOLERANCE, instance_groups
from nodes.values import Material, ShadedScene


def _scene(dent: float = 0.0) -> ShadedScene:
    """Ten grains turned and moved at random, grain 3 dented by ``dent`` mm at one vertex, and a bowl-like box."""
    rng = np.random.default_rng(5)
    grain = trimesh.creation.capsule(height=3.0, radius=1.0, count=[8, 8])
    meshes = []
    for k in range(10):
        rotation = Rotation.random(random_state=k).as_matrix()
        vertices = grain.vertices @ rotation.T + rng.uniform(-50.0, 50.0, 3)
        if k == 3:
            vertices[0] += dent * rotation[:, 2]
        meshes.append(Mesh(vertices, grain.faces, normals=grain.vertex_normals @ rotation.T, name=f"japonica/{k:04d}"))
    meshes.append(Mesh.from_trimesh(trimesh.creation.box(extents=[80, 80, 5]), name="bowl"))
    sigma = tuple(np.full(len(m.vertices), 0.1, np.float32) for m in meshes)
    return ShadedScene(meshes, [Material(name="rice"), Material(name="ceramic")], [0] * 10 + [1], sigma)


def test_rigid_copies_group_and_a_dented_one_does_not():
    assert [g.members.tolist() for g in instance_groups(_scene())] == [list(range(10))]
    dented = instance_groups(_scene(dent=10 * TOLERANCE))  # a dent of a micrometre is a different mesh
    assert [g.members.tolist() for g in dented] == [[0, 1, 2, 4, 5, 6, 7, 8, 9]]
    assert [g.members.tolist() for g in instance_groups(_scene(dent=TOLERANCE / 10))] == [list(range(10))]


def test_a_mirrored_copy_is_not_an_instance():
    scene = _scene()
    flip = np.array([-1.0, 1.0, 1.0])
    mirrored = Mesh(scene.meshes[1].vertices * flip, scene.meshes[1].faces, normals=scene.meshes[1].normals * flip)
    meshes = (scene.meshes[0], mirrored)
    assert instance_groups(ShadedScene(meshes, scene.materials, [0, 0])) == []


def _gltf(data: bytes) -> tuple[dict, bytes]:
    length = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20 : 20 + length]), data[28 + length :]


def _accessor(doc: dict, binary: bytes, index: int) -> np.ndarray:
    accessor = doc["accessors"][index]
    view = doc["bufferViews"][accessor["bufferView"]]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[accessor["type"]]
    data = np.frombuffer(binary, np.float32, accessor["count"] * width, view["byteOffset"])
    return data.reshape(accessor["count"], width)


def test_glb_instances_put_every_grain_where_it_was(gltf_validator):
    scene = _scene(dent=1.0)
    data = export.call(scene=scene, formats=["glb"], basename="s").files["s.glb"]
    report = gltf_validator(data)
    assert report["numErrors"] == 0 and report["numWarnings"] == 0, report["messages"][:5]
    doc, binary = _gltf(data)
    assert "extensionsRequired" not in doc  # core glTF: every reader places the copies
    placed = []
    for node in doc["nodes"][1:]:
        vertices = _accessor(doc, binary, doc["meshes"][node["mesh"]]["primitives"][0]["attributes"]["POSITION"])
        rotation = Rotation.from_quat(node.get("rotation", [0.0, 0.0, 0.0, 1.0])).as_matrix()
        placed.append(vertices @ rotation.T + node.get("translation", [0.0, 0.0, 0.0]))
    assert len(doc["meshes"]) == 3  # the grains' prototype, the dented grain, the bowl
    expected = sorted(scene.meshes, key=lambda m: tuple(m.vertices.mean(0)))
    got = sorted(placed, key=lambda v: tuple(v.mean(0)))
    assert max(np.abs(g - m.vertices).max() for g, m in zip(got, expected)) < 1e-4  # float32 at 50 mm


def test_a_reader_without_extensions_places_every_grain(tmp_path):
    """trimesh (as the file-only checkers read a .glb) supports no glTF extension: it must still draw every
    element where the scene has it, not one prototype at the origin."""
    scene = _scene(dent=1.0)
    path = tmp_path / "s.glb"
    path.write_bytes(export.call(scene=scene, formats=["glb"], basename="s").files["s.glb"])
    loaded = trimesh.load(path)
    to_scene = np.linalg.inv(loaded.graph.get("aggregate")[0])  # the root's Y-up metres back to Z-up mm
    placed = []
    for node in loaded.graph.nodes_geometry:
        world, name = loaded.graph.get(node)
        placed.append(trimesh.transform_points(loaded.geometry[name].vertices, to_scene @ world))
    expected = sorted(scene.meshes, key=lambda m: tuple(m.vertices.mean(0)))
    got = sorted(placed, key=lambda v: tuple(v.mean(0)))
    assert len(got) == len(expected)
    assert max(np.abs(g - m.vertices).max() for g, m in zip(got, expected)) < 1e-4


@pytest.mark.parametrize("fmt", ["usda", "usdc"])
def test_usd_point_instancer_puts_every_grain_where_it_was(tmp_path, fmt):
    from pxr import Usd, UsdGeom

    scene = _scene(dent=1.0)
    path = tmp_path / f"s.{fmt}"
    path.write_bytes(export.call(scene=scene, formats=[fmt], basename="s").files[path.name])
    stage = Usd.Stage.Open(str(path))
    placed = []
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.PointInstancer):
            instancer = UsdGeom.PointInstancer(prim)
            prototype = stage.GetPrimAtPath(instancer.GetPrototypesRel().GetTargets()[0])
            points = np.array(UsdGeom.Mesh(prototype).GetPointsAttr().Get())
            now = Usd.TimeCode.Default()
            for matrix in instancer.ComputeInstanceTransformsAtTime(now, now):
                placed.append(points @ np.array(matrix)[:3, :3] + np.array(matrix)[3, :3])
        elif prim.IsA(UsdGeom.Mesh) and not prim.GetParent().IsA(UsdGeom.PointInstancer):
            placed.append(np.array(UsdGeom.Mesh(prim).GetPointsAttr().Get()))
    expected = sorted(scene.meshes, key=lambda m: tuple(m.vertices.mean(0)))
    got = sorted(placed, key=lambda v: tuple(v.mean(0)))
    assert len(got) == len(expected)
    assert max(np.abs(g - m.vertices).max() for g, m in zip(got, expected)) < 1e-4  # orientationsf: float


def test_instancing_off_writes_a_mesh_per_element():
    scene = _scene()
    files = export.call(scene=scene, formats=["glb"], basename="s", instancing=False).files
    doc, _ = _gltf(files["s.glb"])
    assert len(doc["meshes"]) == len(scene.meshes) and "extensionsRequired" not in doc


def _usdgeom_elements(stage, scene, instancing: bool) -> None:
    """The elements as the UsdGeom API authors them (the writer before its Sdf change block): the reference whose
    specs, fields and field order ``usd_writer._mesh_prim`` must reproduce."""
    from pxr import Gf, Sdf, UsdGeom, UsdShade, Vt

    from nodes.export.instancing import instance_groups
    from nodes.export.usd_writer import prim_names

    looks = [UsdShade.Material(p) for p in stage.GetPrimAtPath("/Scene/Looks").GetChildren()]
    names = prim_names([mesh.name for mesh in scene.meshes], "mesh")
    groups = {int(g.members[0]): g for g in (instance_groups(scene) if instancing else [])}
    copies = {int(k) for g in groups.values() for k in g.members[1:]}

    def mesh_prim(path, k, vertices):
        mesh, geom = scene.meshes[k], UsdGeom.Mesh.Define(stage, path)
        points = np.asarray(vertices, np.float32)
        geom.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
        geom.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(mesh.faces), 3, np.int32)))
        geom.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.asarray(mesh.faces, np.int32).reshape(-1)))
        geom.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        geom.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(np.stack([points.min(0), points.max(0)])))
        if mesh.normals is not None:
            geom.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(np.asarray(mesh.normals, np.float32)))
            geom.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        if mesh.colors is not None:
            color = geom.CreateDisplayColorPrimvar(UsdGeom.Tokens.vertex)
            color.Set(Vt.Vec3fArray.FromNumpy(np.asarray(mesh.colors, np.float32)[:, :3]))
        sigma = UsdGeom.PrimvarsAPI(geom).CreatePrimvar("cdrf_sigma", Sdf.ValueTypeNames.FloatArray, "vertex")
        sigma.Set(Vt.FloatArray.FromNumpy(np.asarray(scene.cdrf_sigma[k], np.float32)))
        own = scene.vertex_transmittance(k)
        if own is not None:  # an egg's membrane: its eye
            tint = UsdGeom.PrimvarsAPI(geom).CreatePrimvar("transmittance", Sdf.ValueTypeNames.Float3Array, "vertex")
            tint.Set(Vt.Vec3fArray.FromNumpy(np.asarray(own, np.float32)))
        UsdShade.MaterialBindingAPI.Apply(geom.GetPrim()).Bind(looks[scene.material_of[k]])
        return geom

    UsdGeom.Scope.Define(stage, "/Scene/Elements")
    for k, mesh in enumerate(scene.meshes):
        if len(mesh.faces) == 0 or k in copies:
            continue
        if k not in groups:
            mesh_prim(f"/Scene/Elements/{names[k]}", k, mesh.vertices)
            continue
        group, path = groups[k], f"/Scene/Elements/{names[k]}_instances"
        instancer = UsdGeom.PointInstancer.Define(stage, path)
        prototype = mesh_prim(f"{path}/{names[k]}", k, mesh.vertices - group.centre)
        instancer.CreatePrototypesRel().SetTargets([prototype.GetPath()])
        instancer.CreateProtoIndicesAttr(Vt.IntArray.FromNumpy(np.zeros(len(group.members), np.int32)))
        instancer.CreatePositionsAttr(Vt.Vec3fArray.FromNumpy(group.positions.astype(np.float32)))
        q = group.quaternions()
        instancer.CreateOrientationsAttr(Vt.QuathArray([Gf.Quath(float(r[3]), *map(float, r[:3])) for r in q]))
        instancer.CreateOrientationsfAttr(Vt.QuatfArray([Gf.Quatf(float(r[3]), *map(float, r[:3])) for r in q]))


@pytest.mark.parametrize("which", ["grains", "dented", "shaded"])
def test_usd_crate_bytes_are_those_of_the_usdgeom_api(which, shaded, tmp_path, monkeypatch):
    """The Sdf change block authors what the UsdGeom API would, field by field in its order: the same .usdc bytes
    (a field out of order, e.g. a normal's interpolation before its value, changes them)."""
    from nodes.export import usd_writer

    scene = {"grains": _scene(), "dented": _scene(dent=1.0), "shaded": shaded}[which]
    for instancing in (True, False):
        fast = usd_writer.usd_bytes(scene, binary=True, instancing=instancing)
        stage = usd_writer.build_stage(scene, instancing)
        stage.RemovePrim("/Scene/Elements")
        _usdgeom_elements(stage, scene, instancing)
        stage.GetRootLayer().Export(str(tmp_path / "reference.usdc"))
        assert fast == (tmp_path / "reference.usdc").read_bytes()


def test_lengths_are_numpy_norms_to_the_bit():
    from nodes.shading.curvature import row_lengths

    rng = np.random.default_rng(2)
    for dtype in (np.float32, np.float64):
        rows = (rng.standard_normal((100_000, 3)) * 10.0 ** rng.uniform(-15, 15, (100_000, 1))).astype(dtype)
        assert np.array_equal(row_lengths(rows), np.linalg.norm(rows, axis=1, keepdims=True))
