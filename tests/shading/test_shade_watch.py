"""A shading edit under ``nodegraph watch`` re-runs shade on the same (frozen, kept) aggregates: their element
meshes are built once, not again for every edit, and the scene comes out the same."""

import numpy as np

from nodegraph.codec import freeze, thaw
from nodes.shading import shade


def test_shading_the_same_aggregates_again_does_not_rebuild_their_meshes(scene_inputs, monkeypatch):
    from nodes.material.cooked import cooked_material

    inputs = {k: freeze(thaw(v)) for k, v in scene_inputs.items()}  # copies: as the executor hands them over
    material = freeze(cooked_material())
    built = []
    for kind in {type(a) for a in inputs["aggregates"]}:
        original = kind.element_mesh

        def counting(self, i, original=original):
            built.append(i)
            return original(self, i)

        monkeypatch.setattr(kind, "element_mesh", counting)
    first = shade.call(**inputs, material=material, baked_ambient=0.3)
    count = len(built)
    assert count == sum(len(a.placement) for a in inputs["aggregates"])
    second = shade.call(**inputs, material=material, baked_ambient=0.5)
    assert len(built) == count  # the second shading reused them
    assert all(np.array_equal(a.vertices, b.vertices) for a, b in zip(first.meshes, second.meshes))
    assert not all(np.array_equal(a.colors, b.colors) for a, b in zip(first.meshes, second.meshes))
