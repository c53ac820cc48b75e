"""A node declared ``overlap`` (a renderer) runs in the main thread while a second thread computes what neither
needs it nor depends on it (``executor.Beside``): both at once, the same results, the failure semantics kept."""

import numpy as np
import pytest

from nodegraph.errors import NodeFailure
from nodegraph.executor import run_recipe
from nodegraph.recipe import parse_recipe

RECIPE = """\
name: overlap
seed: 3
outputs: [render.image, busy.spheres, after.spheres]
nodes:
  pts:
    type: toy_points
    params: {count: 20}
  render:
    type: toy_render
    inputs: {spheres: pts.spheres}
    params: {seconds: 0.3, meet: NAME}
  busy:
    type: toy_busy
    inputs: {spheres: pts.spheres}
    params: {seconds: 0.5, meet: NAME}
  after:
    type: toy_shift
    inputs: {spheres: busy.spheres}
    params: {dx: 1.0}
"""


def run(registry, cache, name, overrides=(), text=RECIPE, **kw):
    recipe = parse_recipe(text.replace("NAME", name), registry, file="overlap.yaml", overrides=list(overrides))
    return run_recipe(recipe, cache=cache, **kw)


def test_the_renderer_runs_beside_the_independent_nodes(registry, cache):
    """Each of the two waits until the other runs (else fails after 5 s): in turn, as before, the first failed."""
    result = run(registry, cache, "beside")
    status = result.status()
    assert status["render"] == status["busy"] == status["after"] == "ran"
    assert result.output("render.image").pixels[0, 0, 0] == 20
    records = {r.node: r for r in result.records}
    # each gets its own CPU: the busy node's core-second is not the renderer's (which only waits)
    assert records["busy"].cpu_seconds >= 0.4
    assert records["render"].cpu_seconds < 0.3
    assert records["render"].seconds < 1.0  # its own wall, not the wait for busy


def test_the_same_results_beside_as_in_turn(registry, cache, tmp_path, monkeypatch):
    from nodegraph.cache import Cache

    beside = run(registry, cache, "alone", out_dir=tmp_path / "beside")
    monkeypatch.setenv("NODEGRAPH_OVERLAP", "off")
    in_turn = run(registry, Cache(tmp_path / "other"), "alone", out_dir=tmp_path / "in_turn")
    assert in_turn.status() == beside.status()
    for ref in ("render.image", "busy.spheres", "after.spheres"):
        a, b = beside.output(ref), in_turn.output(ref)
        assert all(np.array_equal(x, y) for x, y in zip(vars(a).values(), vars(b).values(), strict=True))
    names = sorted(p.name for p in (tmp_path / "beside").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "in_turn").iterdir())
    for name in names:
        if name != "manifest.json":
            assert (tmp_path / "beside" / name).read_bytes() == (tmp_path / "in_turn" / name).read_bytes()


def test_a_node_failing_beside_the_renderer_fails_the_run_and_the_render_is_kept(registry, cache):
    text = RECIPE.replace("type: toy_shift", "type: toy_fail").replace("    params: {dx: 1.0}\n", "")
    with pytest.raises(NodeFailure, match="'after'"):
        run(registry, cache, "alone", text=text)
    again = run(registry, cache, "alone")
    status = again.status()
    assert status["render"] == status["busy"] == "cached" and status["after"] == "ran"


def test_a_failing_renderer_fails_the_run_and_what_ran_beside_it_is_kept(registry, cache):
    with pytest.raises(NodeFailure, match="'render'.*toy render failed"):
        run(registry, cache, "alone", overrides=["render.fail=true"])
    status = run(registry, cache, "alone").status()
    assert status["busy"] == "cached" and status["render"] == "ran"  # busy was running as render failed


def test_the_recording_holds_what_ran_beside_the_renderer(registry, cache, tmp_path):
    """The node beside the renderer logs into the run's recording as in turn: every output of both lanes is there."""
    from rerun.chunk import RrdReader

    result = run(registry, cache, "recorded", rrd=tmp_path / "overlap.rrd")
    assert result.rrd is not None
    reader = RrdReader(str(result.rrd))
    entities = {chunk.entity_path for chunk in reader.stream().to_chunks()}
    assert {"/render/image", "/busy/spheres", "/after/spheres", "/pts/spheres"} <= entities, entities


def test_the_renderer_loads_its_libraries_before_anything_runs_beside_it(registry, cache):
    """Its ``overlap`` callable runs once, in the main thread, before the second thread starts: a library loaded
    by the renderer while the other thread loads one deadlocked (the loader's lock against the GIL)."""
    prepared = registry["toy_render"].overlap.__globals__["RENDER_PREPARED"]  # the plugin file's own module
    loaded = registry["toy_busy"].libraries.__globals__["BUSY_LOADED"]  # the node run beside it: its libraries too
    prepared.clear()
    loaded.clear()
    result = run(registry, cache, "prepared")
    assert result.status()["busy"] == "ran"
    assert prepared == [False]
    assert loaded == [(True, False)]  # once, in the main thread, before the thread beside started
