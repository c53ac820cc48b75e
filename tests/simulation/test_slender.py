"""Long (indica) grains in the run (issue 26, docs/look.md): ``xpbd``'s ``slender`` gives an element m times as
elongated as a japonica grain m× the particles and the run m³× the substeps, so long grains that cross in the pile
come apart instead of staying crossed into each other (the contact step's deep dents were the concave skin)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
from nodes.simulation.cull_crossing import crossing_depths
from nodes.simulation.scenes import grain_mesh
from nodes.simulation.setup import slender_factor

REPO = Path(__file__).resolve().parents[2]
# the reduced rice bowl of ``bench_skin.py --exported`` with the draft's coarser grains (4 variants, 400 faces)
INDICA = [
    "bowl.size=14.0",
    "bowl.depth=12.0",
    "bowl.mound=5.0",
    "variety.variety=indica",
    "grain_spheres.variants=4",
    "grain_volume.resolution=24",
    "grain_mesh.target_faces=400",
]


def test_the_factor_is_the_elongation_over_a_japonica_grains():
    assert slender_factor(grain_mesh(5.0, 3.0, 2.5)) == 1  # japonica, SPEC §1
    assert slender_factor(grain_mesh(3.5, 3.0, 2.5)) == 1  # aromatic: shorter
    assert slender_factor(grain_mesh(11.1, 3.7, 2.6)) == 2  # indica
    assert slender_factor(grain_mesh(4.0, 3.0, 0.4)) == 1  # an ice flake: thin, not long


def crossing(slender: bool, tmp_path) -> np.ndarray:
    """Depths (mm) of the pairs of indica grains that cut into each other after the reduced bowl's run."""
    recipe = load_recipe(
        REPO / "graphs" / "rice_bowl.yaml", default_registry(), INDICA + [f"rice_sim.slender={str(slender).lower()}"]
    )
    result = run_recipe(recipe, outputs=["rice_sim.aggregate"], cache=Cache(tmp_path / "cache"))
    aggregate = result.output("rice_sim.aggregate")
    _, depth = crossing_depths([aggregate.element_mesh(i) for i in range(len(aggregate.placement))])
    return depth[depth > 0]


@pytest.fixture(scope="module")
def slender_depths(tmp_path_factory):
    return crossing(True, tmp_path_factory.mktemp("slender"))


def test_long_grains_do_not_stay_crossed_after_the_run(slender_depths):
    # these draft grains, cutting into each other after the run (pairs, depth p50 / p95 / max in mm; grains 2.6 mm
    # thick): without slender (8 particles, 10 substeps: a012bc0's run) 216 pairs, 0.57 / 1.12 / 1.30; with it 59,
    # 0.33 / 0.91 / 1.01 (the bench's full-resolution grains at 15 % water: p95 1.17 -> 0.66 mm, docs/look.md)
    assert len(slender_depths) <= 120
    assert np.percentile(slender_depths, 95) <= 1.0 and slender_depths.max() <= 1.15
