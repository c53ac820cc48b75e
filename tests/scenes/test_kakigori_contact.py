"""The kakigori's flakes as exported (issues 25, 26), at the reduced size: after the contact step and the removal of
the flakes still crossing, they touch without cutting into each other by either inside test (winding number,
pseudonormal), no face turns over, and each flake keeps its volume. With the cull at D 0.1 mm and eight settle
frames the flakes crossed like an X, the contact step dented them through their whole thickness and they lost up
to 74 % of their volume (docs/contact.md, "Kakigori"); with D 0.05 and one settle frame, 0.064 L deep and a flake
6.5 % short: the tests here fail on both recipes."""

from pathlib import Path

import igl
import numpy as np
import pytest
from scipy.spatial import cKDTree

from benchmarks.bench_scenes import QUICK
from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

REPO = Path(__file__).resolve().parents[2]
SIGNS = {"winding": igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER, "pseudonormal": igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL}


@pytest.fixture(scope="module")
def flakes(tmp_path_factory):
    """(after, before) the contact step: the mesh of each flake the recipe exports, at the reduced size."""
    tmp = tmp_path_factory.mktemp("kakigori")
    recipe = load_recipe(REPO / "graphs" / "kakigori.yaml", default_registry(), QUICK["kakigori"])
    into = str(recipe.nodes["contact"].inputs["aggregate"][0])
    exported = str(recipe.nodes["shade"].inputs["aggregates"][0])
    result = run_recipe(recipe, outputs=["contact.aggregate", into, exported], cache=Cache(tmp / "cache"))
    after, before, kept = result.output("contact.aggregate"), result.output(into), result.output(exported)
    rows = {p.tobytes() for p in kept.placement.positions}
    shown = [i for i in range(len(after.placement)) if after.placement.positions[i].tobytes() in rows]
    assert len(shown) == len(kept.placement) > 100
    return [after.element_mesh(i) for i in shown], [before.element_mesh(i) for i in shown]


def signed_volume(mesh) -> float:
    x, f = mesh.vertices, mesh.faces
    return float(np.einsum("ij,ij->i", x[f[:, 0]], np.cross(x[f[:, 1]], x[f[:, 2]])).sum() / 6.0)


def pair_depths(meshes, sign: str) -> np.ndarray:
    """Per pair of flakes within reach, the deepest vertex of either inside the other, in flake lengths."""
    centres = np.array([m.vertices.mean(axis=0) for m in meshes])
    lengths = np.array([np.ptp(m.vertices, axis=0).max() for m in meshes])
    depths = []
    for i, j in sorted(cKDTree(centres).query_pairs(float(lengths.max()))):
        a, b = meshes[i], meshes[j]
        d_ab = igl.signed_distance(a.vertices, b.vertices, b.faces, sign_type=SIGNS[sign])[0]
        d_ba = igl.signed_distance(b.vertices, a.vertices, a.faces, sign_type=SIGNS[sign])[0]
        depths.append(max(0.0, -float(d_ab.min()), -float(d_ba.min())) / min(lengths[i], lengths[j]))
    return np.array(depths)


@pytest.mark.parametrize("sign", sorted(SIGNS))
def test_flakes_touch_without_cutting(flakes, sign):
    """Issue 25's bars on the pairs within reach: p95 ≤ 0.003 L, max ≤ 0.01 L (crossed flakes: p95 0.02 L; the recipe
    before ``cull_crossing``: max 0.064 L)."""
    after, _ = flakes
    depths = pair_depths(after, sign)
    assert np.percentile(depths, 95) <= 0.003 and depths.max() <= 0.01


def test_flakes_keep_their_volume_and_no_face_turns(flakes):
    after, before = flakes
    errors = np.array([abs(signed_volume(a) / signed_volume(b) - 1.0) for a, b in zip(after, before)])
    # issue 25's bar, every flake within 2 % (the crossed flakes lost up to 74 %; with one settle frame and no
    # flake removed, one ended 6.5 % short here, 16 of 5,062 at full size)
    assert errors.max() <= 0.02
    turned = 0
    for a, b in zip(after, before):
        na = np.cross(
            a.vertices[a.faces[:, 1]] - a.vertices[a.faces[:, 0]], a.vertices[a.faces[:, 2]] - a.vertices[a.faces[:, 0]]
        )
        nb = np.cross(
            b.vertices[b.faces[:, 1]] - b.vertices[b.faces[:, 0]], b.vertices[b.faces[:, 2]] - b.vertices[b.faces[:, 0]]
        )
        turned += int(np.sum(np.einsum("ij,ij->i", na, nb) < 0.0))
    assert turned == 0
