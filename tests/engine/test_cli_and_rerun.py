"""The command line (with a --plugin node module) and the Rerun recording it saves."""

import os
import subprocess
import sys
from pathlib import Path

import datafusion
import pytest
from rerun.chunk import RrdReader

from nodegraph.cli import main

TOY = str(Path(__file__).with_name("toy_nodes.py"))
RECIPE = """\
name: toyrun
seed: 2
effects: [gravity]
outputs: [merge.spheres, surf]
nodes:
  pts:
    type: toy_points
    variants: 2
    params: {count: 8}
  phys:
    type: toy_physics
    inputs: {spheres: pts.spheres}
  merge:
    type: toy_merge
    inputs: {parts: phys.spheres}
  surf:
    type: toy_sphere_mesh
    inputs: {spheres: merge.spheres}
"""


@pytest.fixture
def recipe(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("NODEGRAPH_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "toyrun.yaml"
    path.write_text(RECIPE)
    return path


def cli(*args):
    return main([*args, "--plugin", TOY])


def test_run_writes_outputs_and_a_readable_rrd(recipe, tmp_path, capsys):
    assert cli("run", str(recipe)) == 0
    out = tmp_path / "outputs" / "toyrun"
    assert (out / "merge.spheres.npz").is_file() and (out / "surf.ply").is_file()
    rrd = out / "toyrun.rrd"
    verify = subprocess.run([sys.executable, "-m", "rerun", "rrd", "verify", str(rrd)], capture_output=True, text=True)
    assert verify.returncode == 0, verify.stderr
    reader = RrdReader(str(rrd))
    assert [r.application_id for r in reader.recordings()] == ["nodegraph"]
    store = reader.stream().collect()
    entities = set(store.schema().entity_paths())
    assert {"/pts/0/spheres", "/pts/1/spheres", "/phys/1/spheres", "/merge/spheres", "/surf/mesh"} <= entities
    ctx = datafusion.SessionContext()  # our own context: the global one hung in threaded workers
    table = store.reader(None, ctx=ctx).to_arrow_table()
    assert "/surf/mesh:Mesh3D:vertex_positions" in table.column_names
    assert "/pts/0/spheres:Points3D:radii" in table.column_names


def test_second_run_is_cached_and_summary_shows_it(recipe, capsys):
    assert cli("run", str(recipe), "--no-rrd") == 0
    capsys.readouterr()
    assert cli("run", str(recipe), "--no-rrd") == 0
    err = capsys.readouterr().err
    assert "cached" in err and "ran" not in err.replace("nodegraph run", "")


def test_set_and_output_from_the_command_line(recipe, tmp_path, capsys):
    assert cli("run", str(recipe), "--set", "phys.dt=0.5", "--output", "merge.spheres", "--no-rrd") == 0
    err = capsys.readouterr().err
    assert "surf" not in err and "merge" in err
    assert cli("run", str(recipe), "--set", "phys.dt=5") == 2
    assert "--set:1" in capsys.readouterr().err


def test_check_reports_every_problem_with_exit_status_2(recipe, capsys):
    recipe.write_text(RECIPE.replace("count: 8", "count: -1").replace("type: toy_merge", "type: toy_merj"))
    assert cli("check", str(recipe)) == 2
    err = capsys.readouterr().err
    assert "2 problems" in err and f"{recipe}:9:21" in err and "toy_merge" in err


def test_check_ok_and_nothing_runs(recipe, tmp_path, capsys):
    assert cli("check", str(recipe)) == 0
    assert "OK" in capsys.readouterr().out
    assert not (tmp_path / "cache").exists() and not (tmp_path / "outputs").exists()


def test_a_copied_recipe_names_its_recording_after_its_own_file(recipe, tmp_path):
    """Issue 47: a copy keeps the original's ``name:`` line; its folder followed the copy's file name, its
    recording the original's name."""
    copy = tmp_path / "mycopy.yaml"
    copy.write_text(recipe.read_text())  # name: toyrun
    assert cli("run", str(copy), "-q") == 0
    assert sorted(p.name for p in (tmp_path / "outputs" / "mycopy").glob("*.rrd")) == ["mycopy.rrd"]


def test_nodes_describe_graph(recipe, capsys):
    assert cli("nodes") == 0
    assert "toy_points" in capsys.readouterr().out
    assert cli("describe", "toy_shift") == 0
    out = capsys.readouterr().out
    assert "dx" in out and "mm" in out and "[-10.0, 10.0]" in out
    assert cli("describe", "toy_shfit") == 2
    assert "did you mean 'toy_shift'" in capsys.readouterr().err
    assert cli("describe", "egg_base") == 2  # a step's name, not a type: the step's type line names it
    assert "found by its name in the recipes here" in capsys.readouterr().err


def test_describe_takes_a_step_name_or_the_start_of_a_type(recipe, capsys):
    """A new user reads step names in a recipe (``cooked``), not type names (``cooked_rice``)."""
    assert cli("describe", "merge") == 0  # toyrun.yaml's step 'merge' is a toy_merge
    out = capsys.readouterr().out
    assert out.startswith(f"'merge' is a step of {recipe.name}: node type toy_merge") and "toy_merge  (" in out
    assert cli("describe", "toy_sh") == 0
    assert "'toy_sh' begins node type toy_shift" in capsys.readouterr().out
    assert cli("describe", "merge.nope") == 2  # README's step.setting form: a setting the type lacks is refused
    assert "toy_merge has no setting 'nope'" in capsys.readouterr().err
    assert cli("describe", "toy_p") == 2  # toy_physics, toy_picture, toy_points: named, not guessed
    assert "did you mean 'toy_physics' or 'toy_picture' or 'toy_points'" in capsys.readouterr().err
    assert cli("graph", str(recipe)) == 0
    out = capsys.readouterr().out
    assert "pts (toy_points ×2)" in out and "parts ← phys.spheres" in out
    assert cli("graph", str(recipe), "--dot") == 0
    assert '"phys" -> "merge"' in capsys.readouterr().out


def test_describe_shows_what_the_recipe_sets_beside_the_default(recipe, tmp_path, capsys):
    """Issue 47: ``describe STEP`` showed the type's defaults only (egg_base's diameter 6.5, where the ikura don
    sets 7.75): a step's values in its recipe, and its draft's, stand beside each default."""
    recipe.write_text(RECIPE + "draft:\n  pts.count: 4\n")
    assert cli("describe", "pts") == 0
    out = capsys.readouterr().out
    (count,) = [line for line in out.splitlines() if line.strip().startswith("count ")]
    assert "default 10  recipe 8  --draft 4" in count, count
    (scale,) = [line for line in out.splitlines() if line.strip().startswith("scale ")]
    assert "recipe" not in scale, scale  # not set: the default stands alone
    assert cli("describe", str(recipe), "pts.count") == 0  # describe RECIPE STEP.SETTING
    assert capsys.readouterr().out.splitlines()[2].startswith("count: int  default 10  recipe 8  --draft 4")
    assert cli("describe", str(recipe), "ptz") == 2
    assert "no step 'ptz' in " in capsys.readouterr().err
    # a recipe named without its folder: the nearest recipe, as ``run`` suggests it (a new user's describe)
    assert cli("describe", str(recipe.with_name("toyrn.yaml")), "pts.count") == 2
    assert f"no such recipe; did you mean {recipe}?" in capsys.readouterr().err


def test_failing_node_exit_status_1(recipe, capsys):
    recipe.write_text(
        RECIPE.replace("type: toy_merge", "type: toy_fail")
        .replace("merge.spheres, ", "")
        .replace("{parts: phys.spheres}", "{spheres: phys.spheres}")
    )
    assert cli("run", str(recipe), "--no-rrd") == 1
    err = capsys.readouterr().err
    assert "node 'merge[0]' (type toy_fail) failed" in err


def test_cache_info_and_clear(recipe, tmp_path, capsys):
    cli("run", str(recipe), "--no-rrd")
    capsys.readouterr()
    assert main(["cache", "info"]) == 0
    out = capsys.readouterr().out
    assert "entries" in out
    # a new user moved the cache with NODEGRAPH_CACHE and found the compiled kernels still in ~/.cache: info says where
    assert f"compiled kernels: {os.environ['NUMBA_CACHE_DIR']} (numba's cache; $NUMBA_CACHE_DIR moves it)" in out
    assert main(["cache", "clear"]) == 0
    assert not (tmp_path / "cache").exists()


def test_console_script_runs(recipe, tmp_path):
    done = subprocess.run(
        ["nodegraph", "run", str(recipe), "--plugin", TOY, "--no-cache", "-q"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr


def test_time_varying_node_logs_on_its_own_timeline(recipe, tmp_path):
    recipe.write_text(RECIPE.replace("  surf:\n    type: toy_sphere_mesh", "  surf:\n    type: toy_slow"))
    recipe.write_text(recipe.read_text().replace("outputs: [merge.spheres, surf]", "outputs: [surf]"))
    assert cli("run", str(recipe), "--rrd", str(tmp_path / "t.rrd")) == 0
    store = RrdReader(str(tmp_path / "t.rrd")).stream().collect()
    ctx = datafusion.SessionContext()  # must outlive the query
    table = store.reader("sim_step", contents="/surf/log/energy", ctx=ctx).to_arrow_table()
    assert table.column("sim_step").to_pylist() == list(range(10))
    assert [v[0] for v in table.column("/surf/log/energy:Scalars:scalars").to_pylist()] == [10.0 - s for s in range(10)]


def test_docs_generated_from_declarations(tmp_path, capsys):
    assert cli("docs", "--out", str(tmp_path / "nodes.md")) == 0
    text = (tmp_path / "nodes.md").read_text()
    assert "## `toy_shift`\n" in text and "| `dx` | float | 0.0 | [-10.0, 10.0] | mm |" in text


def test_two_processes_write_bit_identical_outputs(recipe, tmp_path):
    """Determinism across processes (hash randomisation, dict order): hash every output file."""
    import hashlib

    digests = []
    for run_dir in ("a", "b"):
        out = tmp_path / run_dir
        done = subprocess.run(
            [
                sys.executable,
                "-m",
                "nodegraph.cli",
                "run",
                str(recipe),
                "--plugin",
                TOY,
                "--no-cache",
                "--no-rrd",
                "--out-dir",
                str(out),
                "-q",
            ],
            capture_output=True,
            text=True,
            cwd=tmp_path,
        )
        assert done.returncode == 0, done.stderr
        assert (out / "manifest.json").is_file()  # says when it was written: not part of the comparison
        digests.append(
            {
                p.name: hashlib.sha256(p.read_bytes()).hexdigest()
                for p in sorted(out.iterdir())
                if p.name != "manifest.json"
            }
        )
    assert digests[0] == digests[1] and set(digests[0]) == {"merge.spheres.npz", "surf.ply"}


def test_every_value_type_logs_with_its_archetype(tmp_path):
    """Volumes as points + slice (a distance field coloured by depth), meshes as Mesh3D, tables as scalars."""
    import numpy as np

    from nodegraph.rerun_log import RunRecording, log_value
    from nodegraph.values import Mesh, Table
    from nodes.values import DistanceField, Volume

    grid = np.zeros((6, 6, 6))
    grid[1:5, 1:5, 1:5] = 1.0
    recording = RunRecording(tmp_path / "v.rrd", "values")
    log_value(Volume(grid > 0, np.zeros(3), 0.5), recording.logger("/vol"))
    log_value(DistanceField(grid * 2.0, np.zeros(3), 0.5), recording.logger("/field"))
    log_value(Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]), recording.logger("/mesh"))
    log_value(Table({"energy": np.arange(4.0)}, index="step"), recording.logger("/table"))
    recording.close()
    store = RrdReader(str(tmp_path / "v.rrd")).stream().collect()
    columns = set(store.schema().column_names())
    assert {
        "/vol/cells:Points3D:positions",
        "/vol/slice:Tensor:data",
        "/field/cells:Points3D:colors",
        "/mesh:Mesh3D:vertex_positions",
        "/table/energy:Scalars:scalars",
    } <= columns
    assert "/vol/cells:Points3D:colors" not in columns
