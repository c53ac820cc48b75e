"""Fixtures shared by several test folders: a small synthetic aggregate (capsule grains + ikura eggs with
membrane/yolk parts, a bowl) and that aggregate shaded, for the shading and the export tests."""

import numpy as np
import pytest


@pytest.fixture(scope="session")
def scene_inputs():
    import trimesh

    from nodegraph.values import Mesh
    from nodes.elements import base_mesh
    from nodes.shapes import shape
    from nodes.values import Aggregate, ElementLibrary, Placement

    bowl = shape.call(kind="bowl", size=12.0, depth=8.0, mound=2.0, resolution=2)
    egg = base_mesh.call(shape="ikura", subdivisions=1)
    grain = Mesh.from_trimesh(trimesh.creation.capsule(height=3.0, radius=1.0, count=[8, 8]))
    g = np.linspace(-6, 6, 4)
    xy = np.array([(x, y) for x in g for y in g])
    rice = Aggregate(
        Placement(np.c_[xy, np.full(len(xy), -3.0)], np.tile([0, 0, 1.0], (len(xy), 1)), kind_names=("japonica",)),
        (ElementLibrary("japonica", (grain,)),),
    )
    eggs = Aggregate(
        Placement([[0, 0, 0.5], [3, 0, 0.5], [-3, 1, 0.5]], np.tile([0, 0, 1.0], (3, 1)), kind_names=("ikura",)),
        (ElementLibrary("ikura", (egg,)),),
    )
    return {"aggregates": [rice, eggs], "scenery": [bowl["container"]]}


@pytest.fixture(scope="session")
def shaded(scene_inputs):
    from nodes.shading import shade

    return shade.call(**scene_inputs)
