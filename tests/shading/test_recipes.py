"""End to end: graphs/ikura_don.yaml (small with --set overrides) writes .glb/.usdc/.ply/preview.png;
changing only a shade parameter recomputes only shade, export and preview; changing the cooked material's water
content recomputes the simulation and the shading together, not the grains. Full size is slow."""

from pathlib import Path

import pytest
from recipe_sizes import quick_sizes

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

REPO = Path(__file__).resolve().parents[2]
SMALL = [o for o in quick_sizes()["ikura_don"] if not o.startswith("measure.")]  # the benchmark's reduced size


def _run(recipe_name, overrides, tmp_path):
    recipe = load_recipe(REPO / "graphs" / f"{recipe_name}.yaml", default_registry(), overrides)
    return run_recipe(recipe, cache=Cache(tmp_path / "cache"), out_dir=tmp_path / "out")


def test_ikura_don_small_end_to_end_and_shade_only_rerun(tmp_path):
    first = _run("ikura_don", SMALL, tmp_path)
    names = {p.name for p in first.files}
    assert {"ikura_don.glb", "ikura_don.usdc", "ikura_don.ply", "preview.png"} <= names
    second = _run("ikura_don", SMALL + ["shade.baked_ambient=0.5"], tmp_path)
    ran = {r.node for r in second.records if r.status == "ran"}
    assert ran == {"shade", "export", "preview"}
    # One material: `--set cooked.water_content=22` (the recipe's own suggestion) re-runs the rice's simulation
    # and its shading from the same value; the grain library is not modelled again.
    recipe = load_recipe(REPO / "graphs" / "ikura_don.yaml", default_registry(), SMALL + ["cooked.water_content=22"])
    wetter = run_recipe(recipe, outputs=["rice_sim.particles", "shade.scene"], cache=Cache(tmp_path / "cache"))
    ran = {r.node for r in wetter.records if r.status == "ran"}
    assert {"cooked", "rice_sim", "shade"} <= ran and not ran & {"grain_base", "grain_mesh", "rice", "rice_place"}
    particles = [r.output("rice_sim.particles").positions for r in (first, wetter)]
    assert particles[0].shape == particles[1].shape and not (particles[0] == particles[1]).all()
    colours = [r.output("shade.scene").meshes[0].colors for r in (first, wetter)]
    assert colours[0].shape == colours[1].shape and not (colours[0] == colours[1]).all()


@pytest.mark.slow
def test_the_main_job_runs_at_full_size(tmp_path):
    """README's first command, at full size: the only recipe run whole in the suite (each other recipe runs at its
    reduced size in tests/scenes; a full-size run of each costs 50-85 CPU s for no assertion those lack)."""
    result = _run("ikura_don", [], tmp_path)
    assert {"ikura_don.glb", "preview.png"} <= {p.name for p in result.files}
