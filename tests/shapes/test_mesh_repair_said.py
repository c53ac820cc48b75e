"""A user's mesh file that a run repairs is said so, once, naming the file and what changed: by the run (the engine's
warning channel, ``Context.warn``; a run that loads the cached result says it too) and by ``nodegraph check``, at
the parameter's file:line (issue 47: the mesh was repaired silently)."""

import trimesh

from nodegraph.cli import main
from nodes.elements.mesh_files import load_element_mesh

RECIPE = """\
name: meshy
outputs: [shape]
nodes:
  shape: {type: mesh_file, params: {path: cube.ply}}
"""


def inside_out_open_cube(path):
    """A 10 mm cube, inside out, one triangle missing."""
    box = trimesh.creation.box((10.0, 10.0, 10.0))
    mesh = trimesh.Trimesh(box.vertices, box.faces[:, ::-1][1:], process=False)
    path.write_bytes(trimesh.exchange.ply.export_ply(mesh, encoding="ascii"))


def warnings(text: str) -> list[str]:
    return [line for line in text.splitlines() if "was repaired" in line]


def test_a_repaired_mesh_file_is_said_once_by_the_run_the_cached_run_and_check(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    inside_out_open_cube(tmp_path / "cube.ply")
    (tmp_path / "r.yaml").write_text(RECIPE)
    run = ["run", "r.yaml", "--cache-dir", str(tmp_path / "c"), "--no-rrd"]
    for _ in range(2):  # computed, then loaded from the cache
        assert main(run + ["--set", "shape.size=5"]) == 0
        said = warnings(capsys.readouterr().err)
        assert len(said) == 1, said
        assert said[0].startswith(f"warning: shape: {tmp_path / 'cube.ply'} was repaired: ")
        assert "filled holes (1 face(s) added)" in said[0] and "turned its normals outwards" in said[0], said
    assert main(["check", "r.yaml"]) == 0
    checked = warnings(capsys.readouterr().out)
    assert len(checked) == 1 and checked[0].startswith("  warning: r.yaml:4:"), checked
    assert "node 'shape', path: " in checked[0] and "turned its normals outwards" in checked[0], checked


def test_a_closed_mesh_file_says_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "cube.ply").write_bytes(
        trimesh.exchange.ply.export_ply(trimesh.creation.box((10.0, 10.0, 10.0)), encoding="ascii")
    )
    (tmp_path / "r.yaml").write_text(RECIPE)
    assert main(["run", "r.yaml", "--cache-dir", str(tmp_path / "c"), "--no-rrd"]) == 0
    assert main(["check", "r.yaml"]) == 0
    out = capsys.readouterr()
    assert not warnings(out.err + out.out)


def test_an_element_mesh_files_repairs_are_listed(tmp_path):
    box = trimesh.creation.box((4.0, 2.0, 1.0))
    box.invert()
    (tmp_path / "inverted.ply").write_bytes(trimesh.exchange.ply.export_ply(box, encoding="ascii"))
    changes = []
    load_element_mesh(tmp_path / "inverted.ply", changes=changes)
    assert changes == ["turned its normals outwards (it was inside out)"]
