"""A recipe's outputs land in one place whichever folder the command runs in (issue 47, item 6): ``outputs/`` of
its project (a pyproject.toml or .git above it), else beside the recipe; --out-dir as given."""

import json
from pathlib import Path

from nodegraph.cli import main
from nodegraph.output_folder import recipe_folder_name

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


def test_a_copy_with_the_same_name_gets_a_folder_of_its_own(tmp_path, monkeypatch, capsys):
    """Issue 47: two recipe files of one name in one project wrote into the same outputs/<name>/, each run
    overwriting the other's files. The folder's first recipe keeps outputs/<name>/, the copy gets
    outputs/<name>-<hash of its path>/, the same on every run; the run says where in its first line."""
    project = tmp_path / "project"
    (project / "graphs").mkdir(parents=True)
    (project / "mine").mkdir()
    (project / "pyproject.toml").write_text("[project]\nname = 'mine'\n")
    original, copy = project / "graphs" / "toyrun.yaml", project / "mine" / "toyrun.yaml"
    original.write_text(RECIPE)
    copy.write_text(RECIPE)
    monkeypatch.chdir(project)
    folders = []
    for recipe in (original, copy, original, copy):
        capsys.readouterr()
        assert main(["run", str(recipe), "--plugin", TOY, "--cache-dir", str(tmp_path / "cache"), "--no-rrd"]) == 0
        first = capsys.readouterr().err.splitlines()[0]
        assert first.startswith("outputs go to outputs/toyrun")
        folders.append(project / first.removeprefix("outputs go to ").rstrip("/"))
    assert folders[0] == folders[2] == project / "outputs" / "toyrun"
    assert folders[1] == folders[3] != folders[0] and folders[1].name.startswith("toyrun-")
    for folder, recipe in ((folders[0], original), (folders[1], copy)):
        assert (folder / "surf.ply").is_file()
        assert json.loads((folder / "manifest.json").read_text())["recipe_file"] == str(recipe.resolve())


def test_a_copy_under_another_file_name_writes_to_its_own_folder_and_the_original_keeps_its(
    tmp_path, monkeypatch, capsys
):
    """A recipe copied to another file name in the same folder (its ``name:`` unchanged) took over the original's
    outputs/<name>/ and sent the original's next run to a hashed folder. The folder is named from the file:
    outputs/<stem>/ for the copy, outputs/<name>/ for the recipe as written, on every run, drafts alike."""
    project = tmp_path / "project"
    (project / "graphs").mkdir(parents=True)
    (project / "pyproject.toml").write_text("[project]\nname = 'mine'\n")
    original, copy = project / "graphs" / "toyrun.yaml", project / "graphs" / "my_run.yaml"
    original.write_text(RECIPE)
    copy.write_text(RECIPE)
    monkeypatch.chdir(project)
    common = ["--plugin", TOY, "--cache-dir", str(tmp_path / "cache"), "--no-rrd"]
    for recipe, folder in ((copy, "my_run"), (original, "toyrun"), (copy, "my_run")):
        capsys.readouterr()
        assert main(["run", str(recipe), *common]) == 0
        assert capsys.readouterr().err.splitlines()[0] == f"outputs go to outputs/{folder}/"
        manifest = json.loads((project / "outputs" / folder / "manifest.json").read_text())
        assert manifest["recipe_file"].endswith(recipe.name)
    assert sorted(p.name for p in (project / "outputs").iterdir()) == ["my_run", "toyrun"]


def test_a_file_name_that_is_no_plain_folder_name_falls_back_to_the_recipes_name():
    assert recipe_folder_name(Path("graphs/my bowl.yaml"), "rice_bowl", draft=True) == "rice_bowl_draft"
    assert recipe_folder_name(Path("graphs/my_bowl.yaml"), "rice_bowl", draft=False) == "my_bowl"


def test_a_plain_run_never_removes_what_a_set_run_wrote(tmp_path, monkeypatch, capsys):
    """Issue 47: a plain run deleted the files an earlier ``--set`` run had written into the same folder. Each set
    of settings has a folder of its own inside the recipe's (``set_<settings>``), said in the run's first line; a
    plain run, before and after, leaves it as it was; the same settings again find their own files current."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "toyrun.yaml").write_text(RECIPE)
    cache = ("--cache-dir", str(tmp_path / "cache"))
    plain, other = tmp_path / "outputs" / "toyrun", tmp_path / "outputs" / "toyrun" / "set_pts.count=9+phys.dt=0.5"
    assert main(["run", "toyrun.yaml", "--plugin", TOY, *cache, "--no-rrd"]) == 0
    capsys.readouterr()
    settings = ["--set", "pts.count=9", "--set", "phys.dt = 0.5"]
    assert main(["run", "toyrun.yaml", "--plugin", TOY, *cache, "--no-rrd", *settings]) == 0
    assert capsys.readouterr().err.splitlines()[0] == f"outputs go to {other.relative_to(tmp_path)}/"
    theirs = {p.name: p.read_bytes() for p in other.iterdir()}
    assert {"surf.ply", "merge.spheres.npz", "manifest.json"} <= set(theirs)
    assert json.loads((other / "manifest.json").read_text())["overrides"] == ["pts.count=9", "phys.dt = 0.5"]
    assert (plain / "surf.ply").read_bytes() != theirs["surf.ply"]
    assert main(["run", "toyrun.yaml", "--plugin", TOY, *cache, "--no-rrd", "--output", "surf"]) == 0
    assert "stale" not in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in other.iterdir()} == theirs


def test_a_long_setting_gets_a_short_folder_name_of_its_own():
    from pathlib import Path

    from nodegraph.output_folder import SETTINGS_NAME_MAX, settings_folder

    assert settings_folder(Path("o"), []) == Path("o")
    assert settings_folder(Path("o"), ["shade.syrup_color=[0.1, 0.3, 0.9]"]).name == "set_shade.syrup_color=0.1,0.3,0.9"
    long = [f"node.param_{k}={k}" for k in range(12)]
    names = {settings_folder(Path("o"), s).name for s in (long, long[:-1] + ["node.param_11=12"])}
    assert len(names) == 2 and all(len(n) <= SETTINGS_NAME_MAX for n in names)


def test_a_path_setting_keeps_a_readable_folder_name_of_its_own():
    """Issue 47: ``--set mesh.path=scans/cat.obj`` was named ``set_mesh.path=scanscat.obj``, its slashes dropped. A
    path's separators read ``_``, and a name whose characters were replaced ends with a hash, so that
    ``scans/cat.obj`` and ``scans_cat.obj`` never share a folder."""
    from pathlib import Path

    from nodegraph.output_folder import settings_folder

    names = [settings_folder(Path("o"), [f"mesh.path={v}"]).name for v in ("scans/cat.obj", "scans_cat.obj")]
    assert names[0].startswith("set_mesh.path=scans_cat.obj-") and len(names[0]) == len(names[1]) + 9, names
    assert names[1] == "set_mesh.path=scans_cat.obj"
    absolute = settings_folder(Path("o"), ["mesh.path=/home/me/scans/cat.obj"])
    assert absolute.parent == Path("o") and absolute.name.startswith("set_mesh.path=_home_me_scans_cat.obj-")
