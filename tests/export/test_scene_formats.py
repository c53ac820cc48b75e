"""README: each scene recipe writes `.glb`, `.usdc` and `.ply` (issue 47: kakigori and rice + chestnut wrote no
`.usdc`, though usd-core writes their scenes)."""

import re
from pathlib import Path

import pytest

from nodegraph.recipe import load_recipe
from nodegraph.registry import default_registry

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text().splitlines()
# the picture table: each picture's title row (one or two rows above it) names its recipe
GALLERY = [row for i, row in enumerate(README) if any("![" in below for below in README[i + 1 : i + 3])]
SCENES = sorted({name for line in GALLERY for name in re.findall(r"`(\w+)\.yaml`", line)} or {"(none found)"})


@pytest.mark.parametrize("name", SCENES)
def test_every_scene_in_the_readme_exports_glb_usdc_and_ply(name):
    recipe = load_recipe(ROOT / "graphs" / f"{name}.yaml", default_registry())
    formats = [set(e.params["formats"]) for e in recipe.nodes.values() if e.spec.type_name == "export"]
    assert formats and all({"glb", "usdc", "ply"} <= f for f in formats), (name, formats)
