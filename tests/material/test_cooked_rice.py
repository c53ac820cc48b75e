"""One cooked material (issue 23): the simulation and the shading read the same water content, from one node;
the variety drives the grain library. A recipe cannot state either twice, and one that still sets a moved
parameter is told where it lives now."""

from pathlib import Path

import numpy as np
import pytest
import trimesh

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
from nodegraph.errors import RecipeError
from nodegraph.values import Mesh
from nodes.elements import rice_variety
from nodes.material import cooked_rice
from nodes.shading import shade
from nodes.simulation import xpbd
from nodes.values import Aggregate, ElementLibrary, Placement

REPO = Path(__file__).resolve().parents[2]
JAPONICA = rice_variety.call(variety="japonica")


def _grains() -> Aggregate:
    """Three capsule grains stacked loosely on a floor: contact, friction and clumping all act."""
    grain = Mesh.from_trimesh(trimesh.creation.capsule(height=3.0, radius=1.0, count=[8, 8]))
    positions = np.array([[0.0, 0.0, 1.2], [0.4, 0.3, 3.4], [-0.3, 0.2, 5.6]])
    axes = np.array([[1.0, 0.0, 0.2], [0.0, 1.0, 0.1], [1.0, 1.0, 0.0]])
    return Aggregate(Placement(positions, axes, kind_names=("japonica",)), (ElementLibrary("japonica", (grain,)),))


def _simulate(material):
    floor = Mesh.from_trimesh(trimesh.creation.box(extents=(40.0, 40.0, 4.0)).apply_translation((0, 0, -2.0)))
    effects = ("gravity", "contact", "friction", "adhesion", "collider", "moisture")
    out = xpbd.call(
        aggregate=_grains(), material=material, colliders=[floor], effects=effects, frames=6, particles_per_element=4
    )
    return out["particles"].positions


def test_the_material_water_content_moves_both_the_physics_and_the_shading():
    dry, wet = (cooked_rice.call(variety=JAPONICA, water_content=w) for w in (5.0, 22.0))
    assert wet.stiffness_scale < dry.stiffness_scale and wet.sigma0 > dry.sigma0
    assert not np.array_equal(_simulate(dry), _simulate(wet))
    assert np.array_equal(_simulate(dry), _simulate(cooked_rice.call(variety=JAPONICA, water_content=5.0)))
    scenes = [shade.call(aggregates=[_grains()], material=m) for m in (dry, wet)]
    assert not np.array_equal(scenes[0].meshes[0].colors, scenes[1].meshes[0].colors)
    assert scenes[1].materials[0].clearcoat > scenes[0].materials[0].clearcoat


def test_neither_node_has_a_water_content_of_its_own():
    for spec in (xpbd, shade):
        assert "water_content" not in spec.params and "material" in spec.inputs
        with pytest.raises(TypeError, match="moved to parameter 'water_content' of the cooked_rice node"):
            spec.call(aggregate=_grains(), aggregates=[], water_content=22.0)


@pytest.mark.parametrize("override", ["rice_sim.water_content=22", "shade.water_content=22"])
def test_a_recipe_setting_the_old_parameter_is_told_where_the_value_lives(override):
    with pytest.raises(RecipeError) as caught:
        load_recipe(REPO / "graphs" / "ikura_don.yaml", default_registry(), [override])
    (issue,) = caught.value.issues
    text = str(issue)
    cooked_line = next(
        n
        for n, line in enumerate((REPO / "graphs" / "ikura_don.yaml").read_text().splitlines(), 1)
        if "cooked:" in line
    )
    assert text.startswith("--set:1: node '")
    assert f"that node is 'cooked' at {REPO / 'graphs' / 'ikura_don.yaml'}:{cooked_line + 3}:" in text
    assert "--set cooked.water_content=22" in text


def test_every_recipe_states_its_water_content_once():
    """No recipe sets a water content anywhere but on a cooked_rice node, nor a variety but on a rice_variety node."""
    for path in sorted((REPO / "graphs").rglob("*.yaml")):
        recipe = load_recipe(path, default_registry())
        for node_id, entry in recipe.nodes.items():
            if entry.spec.type_name not in ("cooked_rice", "rice_variety"):
                assert not {"water_content", "variety"} & set(entry.params), (path.name, node_id)


def test_the_variety_drives_the_library(tmp_path):
    """``--set variety.variety=aromatic`` builds an aromatic library (kind and 0.7× the length); it used to stay
    japonica because the base mesh, the library kind and the shading each named the variety."""
    small = ["grain_spheres.variants=1", "grain_volume.resolution=16", "grain_mesh.target_faces=200"]
    libraries, bases = {}, {}
    for variety in ("japonica", "aromatic"):
        recipe = load_recipe(
            REPO / "graphs" / "ikura_don.yaml", default_registry(), [*small, f"variety.variety={variety}"]
        )
        outputs = ["rice.library", "grain_base.mesh", "cooked.material"]
        result = run_recipe(recipe, outputs=outputs, cache=Cache(tmp_path / "cache"))
        libraries[variety] = result.output("rice.library")
        bases[variety] = result.output("grain_base.mesh")
        assert result.output("cooked.material").variety == variety
    assert libraries["aromatic"].kind == "aromatic" and libraries["japonica"].kind == "japonica"
    length = {v: np.ptp(mesh.vertices, axis=0)[0] for v, mesh in bases.items()}
    assert length["aromatic"] == pytest.approx(0.7 * length["japonica"], rel=1e-6)
    grown = {v: lib.props["length"][0] for v, lib in libraries.items()}
    assert grown["aromatic"] < 0.85 * grown["japonica"]
