"""base_mesh presets and user mesh files — SPEC §1.1."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nodes.elements import base_mesh, element_library
from nodes.elements.grain_shapes import DEFAULT_SIZE, RICE_VARIETIES, volume_centroid
from nodes.elements.mesh_files import MeshFileError, load_element_mesh

from .conftest import as_trimesh


@pytest.mark.parametrize("variety", sorted(RICE_VARIETIES))
def test_rice_presets_are_closed_centred_and_scaled(variety):
    mesh = base_mesh.call(variety=RICE_VARIETIES[variety])
    tm = as_trimesh(mesh)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    _, centroid = volume_centroid(mesh.vertices, mesh.faces)
    assert np.allclose(centroid, 0.0, atol=1e-9)
    extent = np.ptp(mesh.vertices, axis=0)
    length, _, thickness = DEFAULT_SIZE["rice"]  # a raw Japanese short grain, docs/sizes.md
    assert extent[0] == pytest.approx(length * RICE_VARIETIES[variety].length_factor, rel=1e-6)
    assert extent[0] > extent[1] > extent[2]  # long axis x, thickness z
    assert extent[2] == pytest.approx(thickness, rel=1e-6)


def test_the_variety_is_an_input_a_recipe_states_once():
    """The variety lives on a rice_variety node whose output base_mesh reads (so does the library: its kind)."""
    from nodes.elements import rice_variety

    aromatic = rice_variety.call(variety="aromatic")
    assert aromatic is RICE_VARIETIES["aromatic"] and aromatic.name == "aromatic"
    assert base_mesh.call(variety=aromatic).name == "aromatic"
    unwired = np.ptp(base_mesh.call().vertices, axis=0)[0]
    assert unwired == pytest.approx(DEFAULT_SIZE["rice"][0], rel=1e-6)  # unwired: factor 1
    with pytest.raises(ValueError, match="only read by shape 'rice'"):
        base_mesh.call(shape="ikura", variety=aromatic)
    library = element_library.call(meshes=[base_mesh.call(variety=aromatic)], variety=aromatic)
    assert library.kind == "aromatic"
    with pytest.raises(ValueError, match="leave the parameter kind unset"):
        element_library.call(meshes=[base_mesh.call(variety=aromatic)], variety=aromatic, kind="japonica")
    assert element_library.call(meshes=[base_mesh.call()]).kind == "grain"


def test_ikura_parts_and_yolk_radius():
    mesh = base_mesh.call(shape="ikura", diameter=4.0, lipid_fraction=0.145, eye_gap=0.0)
    assert set(np.unique(mesh.parts)) == {0, 1}
    outer = mesh.vertices[np.unique(mesh.faces[mesh.parts == 0])]
    yolk = mesh.vertices[np.unique(mesh.faces[mesh.parts == 1])]
    r_i = np.linalg.norm(outer, axis=1).max()
    r_o = np.linalg.norm(yolk, axis=1).max()
    assert r_i == pytest.approx(2.0)
    assert r_o == pytest.approx(r_i * 0.145 ** (1 / 3))  # SPEC §1 Reading: r_o = r_i·∛L
    for part in (0, 1):
        shell = as_trimesh(type(mesh)(mesh.vertices, mesh.faces[mesh.parts == part]))
        shell.remove_unreferenced_vertices()
        assert shell.is_watertight and shell.volume > 0


def test_the_ikura_yolk_floats_up_under_the_membrane_as_its_eye():
    """The oil droplet sits off-centre along +z, its top ``eye_gap`` under the membrane; too large a gap is refused
    with what is allowed."""
    mesh = base_mesh.call(shape="ikura", diameter=6.5, lipid_fraction=0.145, eye_gap=0.15)
    yolk = mesh.vertices[np.unique(mesh.faces[mesh.parts == 1])]
    centre = yolk.mean(axis=0)
    assert np.allclose(centre[:2], 0.0, atol=1e-9) and centre[2] > 1.0
    assert 3.25 - yolk[:, 2].max() == pytest.approx(0.15, abs=1e-9)  # the droplet's top under the skin
    assert np.linalg.norm(yolk - centre, axis=1).max() == pytest.approx(3.25 * 0.145 ** (1 / 3))
    problems = base_mesh.check(base_mesh.resolve_params({"shape": "ikura", "eye_gap": 2.0}))
    assert [name for name, _ in problems] == ["eye_gap"] and "allowed 0 ≤ eye_gap <" in problems[0][1]


def test_a_diameter_that_leaves_no_eye_gap_possible_is_named_with_the_diameters_that_fit():
    """A 1 mm egg with the recipe's diameter_sd 0.63: the smallest egg has no radius, so no eye_gap fits; the check
    said ``allowed 0 ≤ eye_gap < -0.0617 mm`` at the eye_gap the user never touched. It names the diameter and the
    diameters that leave the eye_gap room, and the one it names passes."""
    given = {"shape": "ikura", "diameter_sd": 0.63, "eye_gap": 0.15, "lipid_fraction": 0.145}
    problems = dict(base_mesh.check(base_mesh.resolve_params({**given, "diameter": 1.0})))
    assert "eye_gap" not in problems and "diameter_sd" in problems  # the sd's own rule still says its part
    assert "allowed: diameter > 1.89 mm" in problems["diameter"], problems
    fits = dict(base_mesh.check(base_mesh.resolve_params({**given, "diameter": 1.9, "diameter_sd": 0.475})))
    assert not fits, fits


def test_ice_flake_is_thin_irregular_and_depends_on_shape_seed():
    a = base_mesh.call(shape="ice_flake")
    b = base_mesh.call(shape="ice_flake", shape_seed=3)
    tm = as_trimesh(a)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    extent = np.ptp(a.vertices, axis=0)
    assert extent[2] < 0.2 * extent[0]
    assert not np.allclose(a.vertices, b.vertices)  # the outline depends on shape_seed
    rim = a.vertices[:-2, :2] / (np.ptp(a.vertices[:, :2], axis=0) / 2)
    assert np.ptp(np.linalg.norm(rim, axis=1)) > 0.1  # not an ellipse: irregular outline


def test_ice_flake_curls_like_a_shaving():
    """A curled shaving (issue 26): its ends rise above its middle by ``curl`` × half its length; it stays a closed,
    outward solid of the same thickness. The kakigori recipe's shavings are fine (≤ 3.6 mm long) and curled."""
    import yaml

    flat = base_mesh.call(shape="ice_flake", size=(3.0, 2.0, 0.4))
    curled = base_mesh.call(shape="ice_flake", size=(3.0, 2.0, 0.4), curl=0.3)
    tm = as_trimesh(curled)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    assert tm.volume == pytest.approx(as_trimesh(flat).volume, rel=0.02)
    rise = np.ptp(curled.vertices[:, 2]) - np.ptp(flat.vertices[:, 2])
    assert rise > 0.25  # 0.3 × 1.5 mm at the tips of the plain ellipse; flat: 0
    with pytest.raises(ValueError, match="curl"):
        base_mesh.call(shape="rice", curl=0.2)
    recipe = yaml.safe_load((Path(__file__).resolve().parents[2] / "graphs" / "kakigori.yaml").read_text())
    flakes = [n["params"] for n in recipe["nodes"].values() if n.get("params", {}).get("shape") == "ice_flake"]
    assert len(flakes) >= 4
    assert all(p["size"][0] <= 3.6 and p.get("curl", 0.0) > 0 for p in flakes)  # was 4–4.8 mm, flat


def test_user_mesh_is_recentred_and_aligned(tmp_path):
    import trimesh

    box = trimesh.creation.box(extents=(2.0, 6.0, 1.0))
    box.apply_transform(trimesh.transformations.rotation_matrix(0.4, [1, 1, 0]))
    box.apply_translation([1e5, -3e4, 7.0])  # far from the origin
    path = tmp_path / "box.obj"  # written by hand: full float64 precision (STL is float32)
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in box.vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in box.faces.tolist()]
    path.write_text("\n".join(lines) + "\n")
    mesh = base_mesh.call(shape="file", path=str(path))
    extent = np.ptp(mesh.vertices, axis=0)
    assert extent == pytest.approx([6.0, 2.0, 1.0], rel=1e-6)
    assert np.allclose(mesh.vertices.mean(axis=0), 0.0, atol=1e-6)
    assert as_trimesh(mesh).volume == pytest.approx(12.0, rel=1e-9)


def test_inverted_mesh_is_repaired(tmp_path):
    import trimesh

    box = trimesh.creation.box(extents=(3.0, 2.0, 1.0))
    box.invert()
    path = tmp_path / "inverted.ply"
    box.export(path)
    vertices, faces = load_element_mesh(path)
    assert trimesh.Trimesh(vertices, faces, process=False).volume == pytest.approx(6.0)


def test_degenerate_faces_are_dropped(tmp_path):
    import trimesh

    box = trimesh.creation.box(extents=(3.0, 2.0, 1.0))
    faces = np.vstack([box.faces, [[0, 0, 1], [2, 2, 2]]])  # zero-area faces
    path = tmp_path / "degenerate.off"
    trimesh.Trimesh(box.vertices, faces, process=False).export(path)
    vertices, faces = load_element_mesh(path)
    assert len(faces) == 12


def test_open_mesh_is_refused(tmp_path):
    import trimesh

    box = trimesh.creation.box()
    path = tmp_path / "open.stl"
    trimesh.Trimesh(box.vertices, box.faces[:-2], process=False).export(path)
    with pytest.raises(ValueError, match="not closed"):  # refused by its check, before the file is loaded again
        base_mesh.call(shape="file", path=str(path))
    # refused before any work too (`nodegraph check`), naming the file and how to close it
    problems = base_mesh.check(base_mesh.resolve_params({"shape": "file", "path": str(path)}))
    assert [p for p, _ in problems] == ["path"]
    assert "open.stl" in problems[0][1] and "not closed" in problems[0][1] and "Fill Holes" in problems[0][1]


def test_flat_mesh_is_refused(tmp_path):
    # Two triangles back to back: closed, but encloses no volume.
    path = tmp_path / "flat.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n")
    with pytest.raises(MeshFileError, match="zero volume|not closed"):
        load_element_mesh(path)


def test_nan_in_file_is_refused(tmp_path):
    path = tmp_path / "nan.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n")
    with pytest.raises(MeshFileError, match="NaN"):
        load_element_mesh(path)


def test_missing_and_unreadable_files_are_refused(tmp_path):
    import trimesh

    with pytest.raises(MeshFileError, match="no such mesh file"):
        load_element_mesh(tmp_path / "nope.stl")
    junk = tmp_path / "junk.stl"
    junk.write_bytes(b"\x00\x01 not a mesh")
    with pytest.raises(MeshFileError, match="shorter than a binary STL header"):
        load_element_mesh(junk)
    noise = tmp_path / "noise.stl"  # random bytes: trimesh's own error named a missing optional package
    noise.write_bytes(np.random.default_rng(0).bytes(3000))
    with pytest.raises(MeshFileError, match="not an STL file: not ASCII"):
        load_element_mesh(noise)
    mesh = trimesh.creation.icosphere(2)
    vertices = mesh.vertices.copy()
    vertices[3] = np.nan
    trimesh.Trimesh(vertices, mesh.faces, process=False).export(tmp_path / "nan.obj")
    with pytest.raises(MeshFileError, match="1 vertices have NaN or infinite coordinates"):
        load_element_mesh(tmp_path / "nan.obj")


def test_parameter_combinations_are_checked():
    problems = base_mesh.check(base_mesh.resolve_params({"shape": "file"}))
    assert [p for p, _ in problems] == ["path"]
    problems = base_mesh.check(base_mesh.resolve_params({"shape": "ikura", "size": (1.0, 1.0, 1.0)}))
    assert [p for p, _ in problems] == ["size"]


def test_chestnut_pieces_are_knife_cut_quarters_of_a_kernel():
    """A kuri gohan piece (issue 48): a quarter of a 26 mm peeled kernel, 10–20 mm, closed and outward; flat
    knife-cut faces (a large share of its faces coplanar with a neighbour, as on no rounded blob) and a rounded
    back; each variant its own cuts, the same seed the same piece."""
    pieces = [base_mesh.call(seed=s, shape="chestnut", subdivisions=4) for s in range(6)]
    for mesh in pieces:
        tm = as_trimesh(mesh)
        assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
        extent = np.ptp(mesh.vertices, axis=0)
        assert 10.0 < extent[0] < 22.0 and extent[2] > 7.0  # a quarter of a 26 × 23 × 17 mm kernel
        normals = tm.face_normals[tm.face_adjacency]
        flat = np.einsum("ij,ij->i", normals[:, 0], normals[:, 1]) > 1.0 - 1e-9
        assert 0.3 < flat.mean() < 0.9  # cut faces flat, the back curved
        assert tm.volume > 0.99 * tm.convex_hull.volume  # a convex chunk: a kernel cut by planes
    assert len({round(float(as_trimesh(m).volume), 3) for m in pieces}) == len(pieces)  # every variant its own
    again = base_mesh.call(seed=3, shape="chestnut", subdivisions=4)
    assert np.array_equal(again.vertices, pieces[3].vertices)
