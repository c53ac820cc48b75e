"""The ``cut`` node (G's cut rice bunny): a volume fill minus a half-space or a ball keeps fewer elements,
and from the cut preview's camera the inside of the fill is what shows; rice_bunny.yaml wires the cut view."""

from pathlib import Path

import numpy as np
import pytest
import trimesh

from nodegraph.values import Mesh
from nodes.export.mitsuba_scene import Camera, look_at
from nodes.placement import cut
from nodes.values import Aggregate, ElementLibrary, Placement

REPO = Path(__file__).resolve().parents[2]
RADIUS = 15.0  # mm, the ball the elements fill
SPACING = 3.0  # mm between element centres


@pytest.fixture(scope="module")
def ball():
    """A ball filled in volume (cubic grid, 3 mm apart) with spheres of radius 2.2 mm: no line of sight
    passes between them, so only the outer layer shows unless something is cut away."""
    g = np.arange(-RADIUS, RADIUS + 1e-9, SPACING)
    grid = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    centres = grid[np.linalg.norm(grid, axis=1) <= RADIUS - 2.2] + [5.0, -3.0, 20.0]  # anywhere in the scene
    element = Mesh.from_trimesh(trimesh.creation.icosphere(subdivisions=2, radius=2.2), name="grain")
    n = len(centres)
    deformations = np.tile(np.eye(3), (n, 1, 1)) * (1.0 + 0.01 * np.arange(n))[:, None, None]
    return Aggregate(
        Placement(centres, np.tile([0, 0, 1.0], (n, 1)), kind_names=("japonica",)),
        (ElementLibrary("japonica", (element,)),),
        deformations=deformations,
    )


def visible_elements(aggregate: Aggregate, camera: Camera, width: int = 40, height: int = 24) -> np.ndarray:
    """Indices of the elements seen first from the preview's camera: a z-buffer of every element vertex
    splatted into a coarse image (pixels ≈ 2× the vertex spacing, so a front element leaves no hole)."""
    meshes = [aggregate.element_mesh(i).vertices for i in range(len(aggregate.placement))]
    points = np.concatenate(meshes)
    owner = np.repeat(np.arange(len(meshes)), [len(m) for m in meshes])
    origin, target = look_at(points, camera, width / height)
    forward = (target - origin) / np.linalg.norm(target - origin)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = points - origin
    depth = d @ forward
    scale = (width / 2) / np.tan(np.radians(camera.fov) / 2)
    px = np.floor(width / 2 + scale * (d @ right) / depth).astype(int)
    py = np.floor(height / 2 - scale * (d @ up) / depth).astype(int)
    inside = (px >= 0) & (px < width) & (py >= 0) & (py < height)
    pixel = (py * width + px)[inside]
    order = np.lexsort((depth[inside], pixel))  # by pixel, nearest first
    first = np.unique(pixel[order], return_index=True)[1]
    return np.unique(owner[inside][order][first])


def test_plane_cut_keeps_the_far_half_and_shows_the_inside(ball):
    camera = Camera(elevation=20.0, azimuth=0.0, fov=35.0, margin=0.1)  # rice_bunny.yaml's cut_preview
    half = cut.call(aggregate=ball, kind="plane", normal=(0.0, -1.0, 0.0), offset=0.0)
    centre = 0.5 * (ball.placement.positions.min(axis=0) + ball.placement.positions.max(axis=0))
    kept = half.placement.positions
    assert 0.3 * len(ball.placement) < len(kept) < 0.7 * len(ball.placement)
    assert ((kept - centre)[:, 1] >= 0).all()  # the removed side faces the camera (−y)
    survivors = np.flatnonzero(ball.placement.positions[:, 1] >= centre[1])
    assert np.allclose(half.deformations[:, 0, 0], 1.0 + 0.01 * survivors)  # deformations go with their elements

    def depth_inside(aggregate):  # how far below the ball's surface the visible elements lie
        seen = aggregate.placement.positions[visible_elements(aggregate, camera)]
        return RADIUS - np.linalg.norm(seen - centre, axis=1)

    whole, opened = depth_inside(ball), depth_inside(half)
    assert whole.max() < 2 * SPACING + 2.2  # uncut: only the outer layers show
    assert opened.max() > RADIUS / 2 and np.mean(opened > 2 * SPACING + 2.2) > 0.2  # cut: the filled inside


def pieces(positions: np.ndarray, reach: float) -> list[int]:
    """Sizes of the connected pieces of elements whose centres lie closer than ``reach``, largest first."""
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial.distance import cdist

    _, label = connected_components(cdist(positions, positions) < reach, directed=False)
    return sorted(np.bincount(label).tolist(), reverse=True)


@pytest.fixture(scope="module")
def bunny_head():
    """Spheres (radius 2.2 mm, 4 mm apart: neighbours overlap 0.4 mm) in a block resting on the floor (the
    head), and an ear of six above it, 8 mm higher, joined to the block only by the column x = 0, y = −2 (a neck
    grain at z = 12 and the ear's and block's grains beside it): all in front of the default cut's plane (the
    centre plane y = 0, the −y side removed). Cut, the ear hangs in the air unless three removed grains stay."""
    block = [(x, y, z) for x in (-8, -4, 0, 4, 8) for y in (-6, -2, 2, 6) for z in (0, 4, 8)]
    ear = [(0, y, z) for y in (-2, 2) for z in (16, 20, 24)]
    centres = np.array(block + ear + [(0, -2, 12)], float)
    element = Mesh.from_trimesh(trimesh.creation.icosphere(subdivisions=2, radius=2.2), name="grain")
    n = len(centres)
    return Aggregate(
        Placement(centres, np.tile([0, 0, 1.0], (n, 1)), kind_names=("japonica",)),
        (ElementLibrary("japonica", (element,)),),
    )


def test_a_cut_leaves_no_piece_floating(bunny_head):
    """Issue 26: the default cut keeps the three removed grains that join the ear to the head (the fewest),
    ``drop`` removes the ear, ``keep`` leaves it floating above the head as version 1 did."""
    whole = bunny_head.placement.positions
    front = whole[:, 1] < 0
    bridged = cut.call(aggregate=bunny_head)  # the default: islands bridge
    assert pieces(bridged.placement.positions, 4.4) == [len(bridged.placement)]  # one piece (spheres overlap)
    added = {tuple(p) for p in bridged.placement.positions[bridged.placement.positions[:, 1] < 0]}
    assert added == {(0.0, -2.0, 8.0), (0.0, -2.0, 12.0), (0.0, -2.0, 16.0)}
    assert len(bridged.placement) == (~front).sum() + 3
    dropped = cut.call(aggregate=bunny_head, islands="drop")
    assert np.array_equal(dropped.placement.positions, whole[~front & (whole[:, 2] < 12)])  # the block's half
    floating = cut.call(aggregate=bunny_head, islands="keep")
    assert np.array_equal(floating.placement.positions, whole[~front])
    assert pieces(floating.placement.positions, 4.4) == [30, 3]  # the head's half and the ear's, 8 mm apart


@pytest.mark.parametrize("spread", [10.0, 1e4])  # 1e4: the grid's cells grow far past the reach
def test_contact_graph_is_every_pair_of_elements_with_vertices_within_reach(spread):
    from scipy.spatial.distance import cdist

    from nodes.placement.islands import contact_graph

    rng = np.random.default_rng(3)
    sizes = rng.integers(1, 40, size=30)
    centres = rng.uniform(-spread, spread, (30, 3)) * (np.arange(30) % 2)[:, None]  # half of them near 0
    points = np.concatenate([c + rng.normal(0.0, 1.5, (k, 3)) for c, k in zip(centres, sizes)])
    owner = np.repeat(np.arange(30), sizes)
    graph = contact_graph(points, owner, 30, 0.7).toarray()
    start = np.r_[0, np.cumsum(sizes)]
    near = np.array(
        [
            [cdist(points[a:b], points[c:d]).min() <= 0.7 for c, d in zip(start, start[1:])]
            for a, b in zip(start, start[1:])
        ]
    )
    np.fill_diagonal(near, False)
    assert near.sum() > 20 and np.array_equal(graph > 0, near) and set(np.unique(graph)) <= {0.0, 1.0}


def test_sphere_cut_and_bad_cuts(ball):
    centre = 0.5 * (ball.placement.positions.min(axis=0) + ball.placement.positions.max(axis=0))
    hollow = cut.call(aggregate=ball, kind="sphere", center=(0.0, -8.0, 0.0), radius=8.0)
    gone = np.linalg.norm(ball.placement.positions - (centre + [0.0, -8.0, 0.0]), axis=1) <= 8.0
    assert len(hollow.placement) == len(ball.placement) - gone.sum() and gone.sum() > 20
    with pytest.raises(ValueError, match="zero vector"):
        cut.call(aggregate=ball, normal=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="removes every element"):
        cut.call(aggregate=ball, kind="sphere", radius=100.0)


def test_rice_bunny_recipe_has_the_cut_view():
    from nodegraph.api import default_registry, load_recipe

    nodes = load_recipe(REPO / "graphs" / "rice_bunny.yaml", default_registry(), []).nodes
    wires = {
        (node, port): [str(w) for w in nodes[node].inputs[port]]
        for node, port in [("cut", "aggregate"), ("shade_cut", "aggregates"), ("cut_preview", "scene")]
    }
    assert nodes["cut"].spec.type_name == "cut" and nodes["cut_preview"].spec.type_name == "preview"
    assert wires == {
        ("cut", "aggregate"): ["contact.aggregate"],
        ("shade_cut", "aggregates"): ["cut.aggregate"],
        ("cut_preview", "scene"): ["shade_cut.scene"],
    }


def test_rice_bunny_cut_preview_at_a_small_size(tmp_path):
    """The recipe end to end at a small size: the cut view keeps the pressed bunny's grains on the far side of its
    plane, plus at most two in front where they join a piece back to the rest (a piece of two grains 10.8 mm above
    the floor once floated, issue 26), so the kept grains form one piece; and it writes cut_preview.png beside
    the whole bunny's preview."""
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial.distance import cdist

    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    tiny = [f"{node}.{p}={v}" for node in ("preview", "cut_preview") for p, v in (("width", 48), ("height", 36))]
    small = ["bunny.size=16.0", "grain_spheres.variants=2", "grain_volume.resolution=24", "press.frames=2"]
    recipe = load_recipe(REPO / "graphs" / "rice_bunny.yaml", default_registry(), small + tiny)
    result = run_recipe(
        recipe,
        cache=Cache(tmp_path / "cache"),
        out_dir=tmp_path / "out",
        outputs=["contact.aggregate", "cut.aggregate", "preview.image", "cut_preview.image"],
    )
    pressed, opened = result.output("contact.aggregate").placement, result.output("cut.aggregate").placement
    assert 0 < len(opened) < len(pressed) and len(pressed) > 20
    middle = 0.5 * (pressed.positions.min(axis=0) + pressed.positions.max(axis=0))
    far = pressed.positions[pressed.positions[:, 1] >= middle[1]]
    kept = {tuple(p) for p in far} & {tuple(p) for p in opened.positions}
    # at most two far grains go: a grain the 2-frame press left touching nothing is a floating piece (islands)
    assert len(kept) >= len(far) - 2 and len(opened) <= len(kept) + 2
    # one piece: grains touch when vertices of their meshes come within 0.1 grain lengths (the cut's gap)
    aggregate = result.output("cut.aggregate")
    meshes = [aggregate.element_mesh(i).vertices for i in range(len(opened))]
    reach = 0.1 * np.median([np.ptp(m.vertices, axis=0).max() for m in aggregate.libraries[0].meshes])
    touch = np.array([[cdist(a, b).min() < reach for b in meshes] for a in meshes])
    assert connected_components(touch, directed=False)[0] == 1
    assert {"preview.png", "cut_preview.png"} <= {p.name for p in result.files}
