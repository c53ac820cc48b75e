"""mesh_file names the real cause of a bad mesh, and a recipe's relative paths are taken from its folder."""

import numpy as np
import pytest
import trimesh

from nodegraph.api import default_registry, load_recipe
from nodes.shapes import mesh_file


def test_damaged_and_non_finite_meshes_name_their_cause(tmp_path):
    noise = tmp_path / "noise.stl"
    noise.write_bytes(np.random.default_rng(1).bytes(3000))
    with pytest.raises(ValueError, match="not an STL file") as info:
        mesh_file.call(path=str(noise))
    assert "charset" not in str(info.value)
    sphere = trimesh.creation.icosphere(2)
    vertices = sphere.vertices.copy()
    vertices[[3, 7]] = [np.inf, 0, 0]
    trimesh.Trimesh(vertices, sphere.faces, process=False).export(tmp_path / "inf.obj")
    with pytest.raises(ValueError, match="2 vertices have NaN or infinite coordinates"):
        mesh_file.call(path=str(tmp_path / "inf.obj"))


def test_an_open_mesh_does_not_suggest_the_repair_already_on(tmp_path):
    sphere = trimesh.creation.icosphere(3)
    bowl = sphere.faces[sphere.triangles_center[:, 2] < 0.5]  # a cap cut away: too big a hole to fill
    trimesh.Trimesh(sphere.vertices, bowl, process=False).export(tmp_path / "open.stl")
    box = trimesh.creation.box()
    with pytest.raises(ValueError, match="repair \\(on\\) could not close them"):
        mesh_file.call(path=str(tmp_path / "open.stl"), repair=True)
    trimesh.Trimesh(box.vertices, box.faces[:-1], process=False).export(tmp_path / "hole.stl")
    with pytest.raises(ValueError, match="pass repair: true"):
        mesh_file.call(path=str(tmp_path / "hole.stl"), repair=False)


def test_relative_paths_in_a_recipe_resolve_from_its_folder(tmp_path, monkeypatch):
    folder = tmp_path / "project"
    (folder / "meshes").mkdir(parents=True)
    trimesh.creation.icosphere(2).export(folder / "meshes" / "blob.stl")
    recipe = folder / "r.yaml"
    recipe.write_text("outputs: [m]\nnodes:\n  m: {type: mesh_file, params: {path: meshes/blob.stl}}\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    loaded = load_recipe(recipe, default_registry())
    assert loaded.nodes["m"].params["path"] == str(folder.resolve() / "meshes" / "blob.stl")
    # given on the command line, a relative path is the shell's: from the working folder
    trimesh.creation.icosphere(1).export(elsewhere / "mine.stl")
    loaded = load_recipe(recipe, default_registry(), overrides=["m.path=mine.stl"])
    assert loaded.nodes["m"].params["path"] == "mine.stl"


def test_check_refuses_a_path_that_is_not_a_mesh_and_says_which_files_are(tmp_path, capsys):
    from nodegraph.cli import main

    (tmp_path / "README.md").write_text("# not a mesh\n")
    recipe = tmp_path / "r.yaml"
    recipe.write_text(
        "outputs: [m, e]\nnodes:\n  m: {type: mesh_file, params: {path: README.md}}\n"
        "  e: {type: base_mesh, params: {shape: file, path: README.md}}\n"
    )
    assert main(["check", str(recipe)]) == 2
    err = capsys.readouterr().err
    assert f"{recipe}:3:" in err and f"{recipe}:4:" in err  # each node's line
    assert "node 'm', path: README.md is a .md file, not a mesh file; allowed: .stl, .obj, .ply" in err
    assert "node 'e', path: README.md is a .md file" in err


def test_a_copied_recipe_that_misses_its_mesh_says_where_it_looked_and_where_the_shipped_one_is(tmp_path, capsys):
    """Issue 47: graphs/rice_bunny.yaml copied to another folder cannot find ``assets/bunny.ply``; the message names
    the line, the parameter, the path looked at, that a recipe's paths are taken from its folder, and the shipped
    mesh."""
    from pathlib import Path

    from nodegraph.cli import main

    shipped = Path(__file__).resolve().parents[2] / "graphs"
    recipe = tmp_path / "rice_bunny.yaml"
    recipe.write_text((shipped / "rice_bunny.yaml").read_text())
    assert main(["check", str(recipe)]) == 2
    err = capsys.readouterr().err
    line = next(n for n, text in enumerate(recipe.read_text().splitlines(), 1) if "path: assets/bunny.ply" in text)
    assert f"{recipe}:{line}:" in err and "node 'bunny', path: no such file: " in err, err
    assert str(tmp_path / "assets" / "bunny.ply") in err, err
    assert f"a relative path in a recipe is taken from the recipe's folder, {tmp_path}" in err, err
    assert f"the shipped one is {shipped / 'assets' / 'bunny.ply'}" in err, err
