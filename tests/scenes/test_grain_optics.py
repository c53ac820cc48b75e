"""Issue 26: a cooked grain is optically thick — light scatters many times inside it before it leaves, so it
reads as white rice. A recipe whose grains are thinner than a couple of the medium's mean free paths renders
them as glass: rice + chestnut at S's unitless lengths read as mm (grains 0.53 mm thick) looked frosted."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
from nodes.export.look import random_walk_coefficients
from nodes.shading.materials import rice_material

REPO = Path(__file__).resolve().parents[2]
PREVIEWED_RICE = ["ikura_don", "rice_bowl", "onigiri", "onigiri_cylinder", "sushi", "rice_bunny", "rice_chestnut"]
# optical depth σt × thickness across the grain's thinnest axis: ≥ 2 (a grain of real size at 15–18 % water:
# 2.0 mm × 1.36–1.50 mm⁻¹ ≈ 2.7–3.0; rice + chestnut at S's lengths read as mm: 0.53 mm × 1.36 ≈ 0.72)
OPTICALLY_THICK = 2.0


@pytest.mark.parametrize("name", PREVIEWED_RICE)
def test_rice_grains_are_optically_thick(name):
    recipe = load_recipe(REPO / "graphs" / f"{name}.yaml", default_registry(), [])
    assert "preview" in recipe.nodes
    water = next(n.params["water_content"] for n in recipe.nodes.values() if n.spec.type_name == "cooked_rice")
    grain = next(k for k, n in recipe.nodes.items() if n.spec.type_name == "base_mesh" and n.params["shape"] == "rice")
    with tempfile.TemporaryDirectory() as folder:
        mesh = run_recipe(recipe, outputs=[f"{grain}.mesh"], cache=Cache(Path(folder))).output(f"{grain}.mesh")
    thickness = float(np.ptp(np.asarray(mesh.vertices), axis=0).min())
    # the grain behind a refracting skin, which its film's medium stands in for (``look.film_medium``: a grain-thick
    # slab's reflectance and transmittance kept within 0.02)
    material = rice_material(water)
    sigma_t = float(random_walk_coefficients(material.subsurface_color, material.subsurface_radius)[0].mean())
    assert sigma_t * thickness >= OPTICALLY_THICK, f"{name}: grain {thickness:.2f} mm thick, σt {sigma_t:.2f}/mm"
