"""README: each scene recipe writes `.glb` and `.usdc` (issue 47: kakigori and rice + chestnut wrote no `.usdc`,
though usd-core writes their scenes), and no `.ply` unless asked: it repeats the `.glb`'s meshes without their
materials (45 MB of the main job's 213 MB of files per run)."""

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
def test_every_scene_in_the_readme_exports_glb_and_usdc_and_no_ply(name):
    recipe = load_recipe(ROOT / "graphs" / f"{name}.yaml", default_registry())
    formats = [set(e.params["formats"]) for e in recipe.nodes.values() if e.spec.type_name == "export"]
    assert formats and all({"glb", "usdc"} <= f and "ply" not in f for f in formats), (name, formats)


def test_a_copied_recipe_names_its_files_after_its_own_file(tmp_path):
    """Issue 47: a copy of rice_bowl.yaml saved as my_bowl.yaml wrote rice_bowl.glb (and rice_bowl.rrd) into
    outputs/my_bowl/: its export's basename and its name: line were the original's."""
    copy = tmp_path / "my_bowl.yaml"
    copy.write_text((ROOT / "graphs" / "rice_bowl.yaml").read_text())
    recipe = load_recipe(copy, default_registry())
    assert recipe.name == "rice_bowl" and recipe.file_name == "my_bowl"  # the name: line stays a title
    assert recipe.nodes["export"].params["basename"] == "my_bowl"
