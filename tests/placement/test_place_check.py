"""``nodegraph check`` (and run, before any work) weighs a placement's r against the shape it fills (issue 47,
item 2a, 2b): too large for the shape, or so small it would place more elements than a run starts on unasked."""

import re
import subprocess
import sys
from pathlib import Path

from module_listing import RUN_AND_LIST

from nodegraph.cli import main

RICE_BOWL = str(Path(__file__).resolve().parents[2] / "graphs" / "rice_bowl.yaml")


def test_an_r_larger_than_the_shape_is_refused_by_check(capsys):
    assert main(["check", RICE_BOWL, "--set", "rice_place.r=60"]) == 2
    err = capsys.readouterr().err
    assert "--set:1: node 'rice_place', r: 60 is larger than the shape 'rice_layer' (boolean) it fills" in err
    assert "the shape spans 107 mm; allowed: r < 53.4" in err


def test_a_placement_too_large_is_refused_unless_yes(capsys):
    assert main(["check", RICE_BOWL, "--set", "rice_place.r=0.4"]) == 2
    err = capsys.readouterr().err
    assert "node 'rice_place', r: 0.4 would place ≈ 54,913 elements in 'rice_layer'" in err
    assert "r ≥ 0.42 stays under; or run with --yes to go ahead" in err
    assert main(["check", RICE_BOWL, "--set", "rice_place.r=0.4", "--yes"]) == 0
    main(["check", RICE_BOWL, "--set", "rice_place.r=0.42"])  # the r it names passes the placement's rule (the
    assert "node 'rice_place'" not in capsys.readouterr().err  # preview's memory is weighed against the machine's)


def test_a_placement_in_a_derived_shape_is_weighed_too(capsys):
    """Issue 47: a shape made by a boolean of a vessel region (the ikura don's rice layer) had no estimate, so check
    passed an r that places far more than a run starts on unasked."""
    ikura = str(Path(RICE_BOWL).with_name("ikura_don.yaml"))
    assert main(["check", ikura, "--set", "rice_place.r=0.3"]) == 2
    err = capsys.readouterr().err
    counts = []
    for r in (0.3, 0.25):
        if r != 0.3:
            assert main(["check", ikura, "--set", f"rice_place.r={r}"]) == 2
            err = capsys.readouterr().err
        found = re.search(rf"r: {r} would place ≈ ([0-9,]+) elements in 'rice_layer' \(boolean: [0-9,]+ mm³", err)
        assert found, err
        counts.append(int(found.group(1).replace(",", "")))
    # over the 50,000 a run places unasked, and about as the layer's volume / r³ (its surface shell ∝ r less)
    assert counts[0] > 50_000 and 1.5 < counts[1] / counts[0] < (0.3 / 0.25) ** 3, counts
    assert main(["check", ikura, "--set", "egg_place.r=90"]) == 2
    assert "r: 90 is larger than the shape 'egg_layer' (boolean) it fills" in capsys.readouterr().err


def test_run_refuses_it_before_any_work(tmp_path):
    command = [sys.executable, "-m", "nodegraph.cli", "run", RICE_BOWL, "--set", "rice_place.r=0.4"]
    done = subprocess.run(  # the old code ran for minutes: the timeout fails it
        [*command, "--cache-dir", str(tmp_path / "c")], cwd=tmp_path, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 2 and "would place ≈ 54,913 elements" in done.stderr
    assert not (tmp_path / "c").exists() and not (tmp_path / "outputs").exists()


SMALL = """\
name: small_place
seed: 1
outputs: [place.stats]
nodes:
  ball: {type: shape, params: {kind: sphere, size: 4.0, resolution: 2}}
  place: {type: poisson_place, inputs: {shape: ball.mesh}, params: {mode: volume, r: 1.0}}
"""


def test_a_cached_rerun_does_not_weigh_r_again(tmp_path):
    """The check makes the shape's mesh (trimesh: 0.6 CPU s): only when the placement is to run, not on a cached
    re-run (issue 27: ≤ 1.5 s)."""
    (tmp_path / "small.yaml").write_text(SMALL)
    args = [str(tmp_path / "small.yaml"), "--cache-dir", str(tmp_path / "c"), "--no-rrd", "-q"]
    command = [sys.executable, "-c", RUN_AND_LIST, *args]
    first = subprocess.run(command, cwd=tmp_path, check=True, capture_output=True, text=True).stdout.split()
    assert "trimesh" in first
    again = subprocess.run(command, cwd=tmp_path, check=True, capture_output=True, text=True).stdout.split()
    assert "nodegraph.cache" in again and "trimesh" not in again
