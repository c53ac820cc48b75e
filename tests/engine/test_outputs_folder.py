"""A recipe's outputs land in one place whichever folder the command runs in (issue 47, item 6): ``outputs/`` of
its project (a pyproject.toml or .git above it), else beside the recipe; --out-dir as given."""

from nodegraph.cli import main

from .test_cli_and_rerun import RECIPE, TOY


def run_from(folder, recipe, cache):
    folder.mkdir(parents=True, exist_ok=True)
    return main(["run", str(recipe), "--plugin", TOY, "--cache-dir", str(cache), "--no-rrd", "-q"])


def test_outputs_go_to_the_recipes_project_from_any_folder(tmp_path, monkeypatch):
    project = tmp_path / "project"
    (project / "graphs").mkdir(parents=True)
    (project / "pyproject.toml").write_text("[project]\nname = 'mine'\n")
    recipe = project / "graphs" / "toyrun.yaml"
    recipe.write_text(RECIPE)
    for folder in (tmp_path / "elsewhere", project / "graphs", project):
        folder.mkdir(parents=True, exist_ok=True)
        monkeypatch.chdir(folder)
        assert run_from(folder, recipe, tmp_path / "cache") == 0
    assert (project / "outputs" / "toyrun" / "surf.ply").is_file()
    assert not (tmp_path / "elsewhere" / "outputs").exists() and not (project / "graphs" / "outputs").exists()


def test_a_recipe_outside_a_project_writes_beside_itself(tmp_path, monkeypatch):
    loose = tmp_path / "loose"
    loose.mkdir()
    (loose / "toyrun.yaml").write_text(RECIPE)
    monkeypatch.chdir(tmp_path)
    assert run_from(tmp_path, loose / "toyrun.yaml", tmp_path / "cache") == 0
    assert (loose / "outputs" / "toyrun" / "surf.ply").is_file() and not (tmp_path / "outputs").exists()
