"""Issue 47: ``nodegraph check`` refuses a mesh file that exists and has the right format but is no closed mesh
(no triangles; one open triangle), at ``path``, with the reader's reason: it was a 50-line traceback from the
estimate, which reads the shape to weigh the placement."""

from __future__ import annotations

from pathlib import Path

import pytest

from nodegraph.api import default_registry, load_recipe
from nodegraph.errors import RecipeError

ROOT = Path(__file__).resolve().parents[2]
TRIANGLE = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
TRIANGLE += "endloop\nendfacet\nendsolid t\n"


@pytest.mark.parametrize(
    ("content", "reason"), [("solid x\n", "holds no triangles"), (TRIANGLE, "the mesh has holes (not watertight)")]
)
def test_check_refuses_a_file_that_is_no_closed_mesh(tmp_path, content, reason):
    mesh = tmp_path / "bad.stl"
    mesh.write_text(content)
    with pytest.raises(RecipeError) as caught:
        load_recipe(ROOT / "graphs" / "rice_bunny.yaml", default_registry(), [f"bunny.path={mesh}"], work=True)
    text = str(caught.value)
    assert "--set:1: node 'bunny', path:" in text and reason in text
    assert "Traceback" not in text
