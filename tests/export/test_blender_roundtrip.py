"""The exported .glb and .usdc in Blender 4.5 with the repository's add-on (blender/nodegraph_import): object and
vertex counts, the eggs' and ice's transmission and IOR, the rice's subsurface weight and radius, and a tiny
Cycles render that is not black.

Blender runs as the ``bpy`` module in its own venv (bpy pins numpy 1.26; the project uses numpy 2), made by
``tools/make_blender_venv.sh``; its Python is ``$NODEGRAPH_BLENDER_PYTHON`` or ``.venv-blender/bin/python``.
Without it the test is skipped and says how to make it.
"""

import json
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from nodes.export import export
from nodes.export.look import has_film, has_skin, is_volumetric

REPO = Path(__file__).resolve().parents[2]
SCRIPT = Path(__file__).with_name("blender_roundtrip.py")


def blender_python() -> Path | None:
    path = Path(os.environ.get("NODEGRAPH_BLENDER_PYTHON", REPO / ".venv-blender" / "bin" / "python"))
    return path if path.exists() else None


pytestmark = pytest.mark.skipif(
    blender_python() is None,
    reason="no Blender venv: make it with tools/make_blender_venv.sh (or set NODEGRAPH_BLENDER_PYTHON "
    "to a Python that has bpy 4.5)",
)


@pytest.fixture(scope="module")
def dish(scene_inputs):
    """The shared small dish (grains, three eggs, a bowl) with two ice flakes, shaded by the shade node."""
    import trimesh

    from nodegraph.values import Mesh
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade
    from nodes.values import Aggregate, ElementLibrary, Placement

    flake = Mesh.from_trimesh(trimesh.creation.box(extents=[2.0, 1.5, 0.4]))
    ice = Aggregate(
        Placement([[-4.0, -4.0, 2.0], [4.0, 4.0, 2.0]], np.tile([0, 0, 1.0], (2, 1)), kind_names=("ice",)),
        (ElementLibrary("ice", (flake,)),),
    )
    return shade.call(
        aggregates=[*scene_inputs["aggregates"], ice], scenery=scene_inputs["scenery"], material=cooked_material()
    )


def _in_blender(path: Path, tmp_path: Path) -> dict:
    report = tmp_path / f"{path.suffix[1:]}.json"
    done = subprocess.run(
        [str(blender_python()), str(SCRIPT), str(path), str(report), str(tmp_path / f"{path.suffix[1:]}.png")],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(report.read_text())


@pytest.mark.parametrize("fmt", ["glb", "usdc"])
def test_blender_sees_the_whole_look(dish, tmp_path, fmt):
    path = tmp_path / f"dish.{fmt}"
    path.write_bytes(export.call(scene=dish, formats=[fmt], basename="dish").files[path.name])
    got = _in_blender(path, tmp_path)
    exported = [m for m in dish.meshes if len(m.faces)]
    assert got["meshes"] == len(exported)
    assert got["vertices"] == sum(len(m.vertices) for m in exported)
    skins = {dish.materials[k].name for k in dish.material_of if dish.materials[k].name.startswith("ikura_")}
    skins.discard("ikura_yolk")  # each egg's tint: its membrane, one mesh (its eye in its COLOR_0)
    assert got["mesh_data"] == 4 + len(skins)  # instanced: a grain, a yolk, an ice flake, the bowl, and the skins
    materials = got["materials"]
    assert set(materials) == {m.name for m in dish.materials}  # clean names, no m0000N_ prefix
    for material in dish.materials:
        seen = materials[material.name]
        if is_volumetric(material):  # rice, yolks, ice: the preview's clear skin (or none) over its medium
            assert seen["transmission"] == 1.0 and seen["alpha"] == 1.0 and seen["base_color"] == [1.0, 1.0, 1.0]
            assert seen["volume"] and seen["scatters"] and seen["subsurface"] == 0.0
            if has_skin(material):  # relative to what it sits in (the yolk in the egg's fluid): no stack of IORs
                assert seen["ior"] == pytest.approx(material.ior / material.exterior_ior, abs=1e-6)
            else:  # shaved ice, rice's film: an index-matched boundary, as the preview's null one
                assert seen["ior"] == 1.0 and seen["roughness"] == 0.0
            if has_film(material):  # rice: the film reflects as a coat at the rice's IOR, as the preview's film pass
                assert seen["coat_weight"] == 1.0 and seen["coat_ior"] == pytest.approx(material.ior, abs=1e-6)
            else:
                assert seen["coat_weight"] == 0.0
        elif material.transmission > 0:  # the egg's membrane: refracts, not a see-through ghost
            assert seen["transmission"] == pytest.approx(material.transmission, abs=1e-6)
            assert seen["ior"] == pytest.approx(material.ior, abs=1e-6)
            assert seen["alpha"] == 1.0 and not seen["scatters"]
            # Cycles tints each crossing by √base colour: in and out keep the colour, as the preview's skin does; the
            # .glb's membranes carry it per vertex (their eye): base colour × COLOR_0, the base the palest it reaches
            index = [m.name for m in dish.materials].index(material.name)
            own = [dish.vertex_transmittance(k) for k in np.flatnonzero(dish.material_of == index)]
            if fmt == "glb" and any(t is not None for t in own):
                assert seen["vertex_color"]
                peak = np.concatenate([t for t in own if t is not None]).max(axis=0)
                assert seen["base_color"] == pytest.approx(peak, abs=1e-5)
            else:
                assert seen["base_color"] == pytest.approx(material.subsurface_color, abs=1e-6)
            # one reflecting skin, as the preview's one dielectric: Cycles' transmission lobe reflects by Fresnel at
            # the IOR whatever the Specular IOR Level, so no coat over it (with one, the eggs reflected twice)
            assert seen["coat_weight"] == 0.0
            assert seen["roughness"] == pytest.approx(material.transmission_roughness, abs=1e-6)
        elif material.name == "ceramic":  # a glaze reflects only at its coat: no satin lobe of its own (issue 48)
            assert seen["specular_level"] == 0.0 and seen["coat_weight"] == 1.0 and seen["roughness"] == 1.0
        elif material.subsurface > 0:  # scatters light
            assert seen["subsurface"] == pytest.approx(material.subsurface, abs=1e-6)
            assert seen["subsurface_radius"] == pytest.approx(material.subsurface_radius, abs=1e-6)
            assert seen["subsurface_scale"] == pytest.approx(1e-3)  # mm in Blender's metres
    kinds = {re.sub(r"_.*", "", m.name) for m in dish.materials if m.transmission > 0}
    assert {"ikura", "ice"} <= kinds and any(is_volumetric(m) and m.transmission == 0 for m in dish.materials)
    assert got["render_mean"] > 0.02  # lit, not black
