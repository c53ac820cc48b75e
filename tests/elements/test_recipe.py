"""graphs/rice_grains.yaml end to end through the engine, shrunk by overrides (SPEC §1)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
from nodegraph.codec import decode, encode

RECIPE = Path(__file__).resolve().parents[2] / "graphs" / "rice_grains.yaml"


def test_rice_grains_recipe_builds_a_cached_library(tmp_path):
    overrides = ["japonica_spheres.variants=3", "japonica_volume.resolution=24", "japonica_grain.target_faces=400"]
    recipe = load_recipe(RECIPE, default_registry(), overrides=overrides)
    cache = Cache(tmp_path / "cache")
    first = run_recipe(recipe, outputs=["japonica.library"], cache=cache)
    library = first.output("japonica.library")
    assert library.kind == "japonica" and len(library) == 3
    assert np.allclose(library.props["expansion"], 1.5)  # the japonica preset P
    assert len({m.vertices.shape for m in library.meshes}) > 1 or not np.allclose(
        library.meshes[0].vertices, library.meshes[1].vertices
    )  # three distinct grains
    assert all(len(m.faces) <= 400 * 1.15**3 for m in library.meshes)
    decode(encode(library))  # the library and its GrainMesh values store without pickle
    again = run_recipe(recipe, outputs=["japonica.library"], cache=cache)
    assert encode(again.output("japonica.library")) == encode(library)  # cached and bit-identical
