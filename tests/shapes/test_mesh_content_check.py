"""Issue 47: ``nodegraph check`` refuses a mesh file whose content is not the format its extension claims (a text
file renamed to .stl or .ply), from its first bytes, naming the file and what was found; real meshes pass."""

from __future__ import annotations

import pytest
import trimesh

from nodegraph.api import default_registry, parse_recipe
from nodegraph.errors import RecipeError

RECIPE = """
name: sniff
outputs: [shape.mesh]
nodes:
  shape:
    type: mesh_file
    params: {{path: {path}}}
"""


def content_problem(path):
    """``mesh_io.content_problem``, imported at the call (the test's rule through ``check`` needs none)."""
    from nodes.mesh_io import content_problem

    return content_problem(path)


TEXT = b"These are my notes on rice.\nNot a mesh.\n"


@pytest.mark.parametrize("suffix", [".stl", ".ply", ".obj", ".off", ".glb", ".gltf"])
def test_a_renamed_text_file_is_refused_by_check(tmp_path, suffix):
    notes = tmp_path / f"notes{suffix}"
    notes.write_bytes(TEXT)
    with pytest.raises(RecipeError) as caught:
        parse_recipe(RECIPE.format(path=notes), default_registry(), file=str(tmp_path / "sniff.yaml"))
    text = str(caught.value)
    assert "sniff.yaml:7:" in text and "node 'shape', path:" in text
    assert f"notes{suffix} is not" in text and "found text beginning 'These are my notes on rice.'" in text


def test_binary_noise_named_ply_says_what_it_found(tmp_path):
    noise = tmp_path / "noise.ply"
    noise.write_bytes(bytes(range(256)) * 4)
    assert content_problem(noise) == (
        "noise.ply is not a PLY file: a PLY file starts with 'ply'; found binary data beginning "
        "b'\\x00\\x01\\x02\\x03\\x04\\x05\\x06\\x07'"
    )


def test_a_binary_stl_with_the_wrong_triangle_count_is_refused(tmp_path):
    path = tmp_path / "cut.stl"
    trimesh.creation.icosphere(1).export(path)
    path.write_bytes(path.read_bytes()[:-50])  # one triangle short of its header's count
    assert "header counts 80 triangles" in content_problem(path)


@pytest.mark.parametrize("suffix", [".stl", ".ply", ".obj", ".off", ".glb"])
def test_real_meshes_pass(tmp_path, suffix):
    path = tmp_path / f"ball{suffix}"
    trimesh.creation.icosphere(1).export(path)
    assert content_problem(path) is None
    parse_recipe(RECIPE.format(path=path), default_registry(), file=str(tmp_path / "sniff.yaml"))


def test_an_ascii_stl_passes(tmp_path):
    path = tmp_path / "ball.stl"
    path.write_bytes(trimesh.exchange.stl.export_stl_ascii(trimesh.creation.icosphere(1)).encode())
    assert content_problem(path) is None
