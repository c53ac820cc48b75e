"""Pull-based runs, cache reuse and selective invalidation, variants, effects, failures, determinism."""

import json
import os

import numpy as np
import pytest

from nodegraph import codec
from nodegraph.errors import NodeFailure
from nodegraph.executor import Instance, run_recipe
from nodegraph.recipe import parse_recipe

RECIPE = """\
name: toy
seed: 3
effects: [gravity]
outputs: [merge.spheres]
nodes:
  pts:
    type: toy_points
    params: {count: 20, scale: 2.0}
  shifted:
    type: toy_shift
    inputs: {spheres: pts.spheres}
    params: {dx: 1.5}
  phys:
    type: toy_physics
    inputs: {spheres: shifted.spheres}
  merge:
    type: toy_merge
    inputs: {parts: [pts.spheres, phys.spheres]}
  mesh:
    type: toy_mesh
  measure:
    type: toy_measure
    inputs: {mesh: mesh.mesh}
"""


def run(registry, cache, overrides=(), outputs=None, text=RECIPE, **kw):
    recipe = parse_recipe(text, registry, file="toy.yaml", overrides=list(overrides))
    return run_recipe(recipe, cache=cache, outputs=outputs, **kw)


def test_first_run_runs_second_is_cached(registry, cache):
    first = run(registry, cache)
    assert first.status() == {"pts": "ran", "shifted": "ran", "phys": "ran", "merge": "ran"}
    second = run(registry, cache)
    assert set(second.status().values()) == {"cached"}
    a, b = first.output("merge.spheres"), second.output("merge.spheres")
    assert codec.content_hash(a) == codec.content_hash(b)


def test_changing_a_parameter_recomputes_only_downstream(registry, cache):
    run(registry, cache)
    again = run(registry, cache, overrides=["shifted.dx=2.0"])
    assert again.status() == {"pts": "cached", "shifted": "ran", "phys": "ran", "merge": "ran"}


def test_changing_the_seed_recomputes_only_random_nodes_and_dependents(registry, cache):
    run(registry, cache, outputs=["measure"])
    run(registry, cache)
    again = run(registry, cache, overrides=["seed=4"], outputs=["merge", "measure"])
    status = again.status()
    assert status["pts"] == "ran" and status["merge"] == "ran"
    assert status["mesh"] == "cached" and status["measure"] == "cached"


def test_pull_based_only_runs_upstream_of_requested_output(registry, cache):
    result = run(registry, cache, outputs=["shifted.spheres"])
    assert result.status() == {"pts": "ran", "shifted": "ran"}
    result = run(registry, cache, outputs=["measure.table"])
    assert result.status() == {"mesh": "ran", "measure": "ran"}


def test_cached_nodes_not_needed_are_not_loaded(registry, cache, monkeypatch):
    run(registry, cache)
    loads = []
    original = cache.load
    monkeypatch.setattr(cache, "load", lambda key, expected: loads.append(key) or original(key, expected))
    result = run(registry, cache, overrides=["shifted.dx=3.0"])
    assert result.status()["pts"] == "cached"
    assert len(loads) == 1  # pts is loaded once, for shifted; phys and merge run


def test_effects_reach_only_implementing_nodes_and_enter_their_key(registry, cache):
    first = run(registry, cache)
    table = first.values[Instance("phys")]["effects"]
    assert bool(table.columns["gravity"][0]) and table.columns["count"][0] == 1
    no_gravity = RECIPE.replace("effects: [gravity]", "effects: []")
    second = run(registry, cache, text=no_gravity)
    assert second.status() == {"pts": "cached", "shifted": "cached", "phys": "ran", "merge": "ran"}
    assert not second.values[Instance("phys")]["effects"].columns["gravity"][0]
    moved = second.output("phys.spheres").centers - first.output("shifted.spheres").centers
    assert np.all(moved == 0)  # no gravity kernel ran


def test_same_seed_is_bit_identical_and_other_seed_differs(registry):
    a = run(registry, None).output("merge.spheres")
    b = run(registry, None).output("merge.spheres")
    c = run(registry, None, overrides=["seed=5"]).output("merge.spheres")
    assert codec.content_hash(a) == codec.content_hash(b)
    assert codec.content_hash(a) != codec.content_hash(c)


def test_outputs_are_read_only(registry, cache):
    spheres = run(registry, cache, outputs=["pts"]).output("pts")
    with pytest.raises(ValueError):
        spheres.centers[0, 0] = 1.0


FAMILY = """\
seed: 1
outputs: [merge]
nodes:
  pts:
    type: toy_points
    variants: 4
    params: {count: 5}
  shifted:
    type: toy_shift
    inputs: {spheres: pts.spheres}
    params: {dx: 1.0}
  merge:
    type: toy_merge
    inputs: {parts: shifted.spheres}
"""


def test_variants_map_and_gather_with_a_cache_entry_each(registry, cache):
    result = run(registry, cache, text=FAMILY)
    status = result.status()
    assert [status[f"pts[{i}]"] for i in range(4)] == ["ran"] * 4
    assert [status[f"shifted[{i}]"] for i in range(4)] == ["ran"] * 4
    parts = result.output("pts.spheres")
    assert len(parts) == 4 and len({codec.content_hash(p) for p in parts}) == 4  # distinct seeds
    assert list(result.values[Instance("merge")]["stats"].columns["count"]) == [5, 5, 5, 5]
    assert len({result.keys[Instance("shifted", i)] for i in range(4)}) == 4
    grown = run(registry, cache, text=FAMILY, overrides=["pts.variants=6"])
    status = grown.status()
    assert [status[f"pts[{i}]"] for i in range(6)] == ["cached"] * 4 + ["ran"] * 2
    assert status["merge"] == "ran"


def test_failing_node_names_itself_and_keeps_earlier_results(registry, cache):
    text = RECIPE.replace("type: toy_physics", "type: toy_fail").replace("effects: [gravity]", "effects: []")
    with pytest.raises(NodeFailure) as info:
        run(registry, cache, text=text)
    message = str(info.value)
    assert "'phys'" in message and "toy_fail" in message and "radius must be positive" in message
    assert message.startswith("toy.yaml:13:")  # where the failing node is declared
    fixed = run(registry, cache)
    assert fixed.status()["pts"] == "cached" and fixed.status()["shifted"] == "cached"


def test_node_returning_wrong_type_is_a_clear_failure(registry, cache, monkeypatch):
    recipe = parse_recipe(RECIPE, registry, file="toy.yaml")
    spec = recipe.nodes["shifted"].spec
    monkeypatch.setattr(recipe.nodes["shifted"], "spec", type(spec)(**{**spec.__dict__, "run": lambda ctx, **kw: 42}))
    with pytest.raises(NodeFailure, match="output 'spheres' is a int, declared SphereSet"):
        run_recipe(recipe, cache=cache)


def test_outputs_written_to_directory(registry, cache, tmp_path):
    text = RECIPE.replace("outputs: [merge.spheres]", "outputs: [merge.spheres, mesh]")
    result = run(registry, cache, text=text, out_dir=tmp_path / "out")
    names = sorted(p.name for p in result.files)
    assert names == ["merge.spheres.npz", "mesh.ply"]
    loaded = np.load(tmp_path / "out" / "merge.spheres.npz")
    assert sorted(loaded.files) == ["centers", "radii"]  # named by field, readable without nodegraph
    assert np.array_equal(loaded["centers"], result.output("merge.spheres").centers)
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert set(manifest["files"]) == set(names) and manifest["seed"] == result.recipe.seed
    assert manifest["files"]["mesh.ply"]["bytes"] == (tmp_path / "out" / "mesh.ply").stat().st_size
    umask = os.umask(0)
    os.umask(umask)
    assert all(p.stat().st_mode & 0o777 == 0o666 & ~umask for p in result.files)  # as open() makes them, not 0600


def test_tables_are_written_as_csv(tmp_path):
    from nodegraph.output_files import write_output
    from nodegraph.values import Table

    table = Table({"placed": np.array([12, 7]), "ratio": np.array([1.0 / 3.0, 2.5])})
    (path,) = write_output(table, tmp_path, "stats")
    assert path.name == "stats.csv"
    rows = path.read_text().splitlines()
    assert rows[0] == "placed,ratio" and float(rows[1].split(",")[1]) == 1.0 / 3.0


def test_progress_bars_nest_on_a_terminal(registry, cache):
    import io

    from rich.console import Console

    from nodegraph.report import Reporter

    buffer = io.StringIO()
    reporter = Reporter(console=Console(file=buffer, force_terminal=True, width=100))
    text = RECIPE.replace("type: toy_shift", "type: toy_slow").replace("{dx: 1.5}", "{seconds: 0.05}")
    result = run(registry, cache, text=text, reporter=reporter)
    assert result.status()["shifted"] == "ran"
    assert "shifted sleeping" in buffer.getvalue()  # the node's own bar was drawn inside the run's


def test_the_closing_table_gives_each_node_its_cpu_seconds(registry, cache):
    """A node's CPU seconds (all the process's threads while it ran) stand beside its wall time: on a shared
    machine they are the figure to compare. Cached nodes have none."""
    from nodegraph.report import Reporter, parse_duration

    first = run(registry, cache)
    ran = [r for r in first.records if r.status == "ran"]
    assert ran and all(r.cpu_seconds is not None and r.cpu_seconds >= 0.0 for r in ran)
    assert all(r.cpu_seconds is None for r in run(registry, cache).records)
    reporter = Reporter(quiet=True)
    for record in first.records:
        reporter.record(record)
    table = reporter.summary(width=200)
    assert [c.header for c in table.columns][3:5] == ["wall time", "CPU time"]
    assert all(parse_duration(cell) >= 0.0 for cell in table.columns[4].cells)


def test_images_are_written_as_png_at_zlibs_fastest_level(tmp_path):
    """The preview's PNG is written after its render, on the run's critical path: zlib level 1 (0.06 CPU s for
    1280 × 720, not 0.25 at level 6), the same pixels."""
    import imageio.v3 as iio

    from nodegraph.output_files import write_output
    from nodegraph.values import Image

    pixels = np.random.default_rng(0).integers(0, 256, (90, 160, 3), dtype=np.uint8)
    (path,) = write_output(Image(pixels), tmp_path, "picture")
    data = path.read_bytes()
    idat = data.index(b"IDAT")
    assert data[idat + 4 : idat + 6] == b"\x78\x01"  # the zlib header of level 1 (level 6: 78 9c)
    assert np.array_equal(iio.imread(path), pixels)
