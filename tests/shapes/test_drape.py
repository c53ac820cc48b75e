"""The fish topping (``drape``, ``plate_drape``): a Kirchhoff plate resting on an aggregate's top — the
obstacle problem's conditions, the plate's scaling with stiffness and load, and the draped slab on a
nigiri-like block: closed, resting on it without entering it, its ends drooping, its length kept."""

import importlib

import igl
import numpy as np
import pytest
import trimesh

from nodegraph.values import Mesh
from nodes.shapes import drape
from nodes.shapes.plate_drape import PlateGrid, drape_plate, plate_stiffness
from nodes.shapes.solids import rounded_block
from nodes.values import Aggregate, ElementLibrary, Placement


@pytest.fixture(scope="module")
def block():
    """A nigiri's rice as one element: a rounded block 50 × 23 × 19 mm (the sushi recipe's shape)."""
    mesh = rounded_block((50.0, 23.0, 19.0), 4.0, subdivisions=5)
    library = ElementLibrary("japonica", (Mesh.from_trimesh(mesh),))
    return Aggregate(Placement([[0.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]], kind_names=("japonica",)), (library,)), mesh


def _strip(grid: PlateGrid, half: float) -> np.ndarray:
    """A flat support at z = 0 under |u| < half, nothing beyond: the plate overhangs both ends."""
    u = grid.u[:, None] + 0 * grid.v[None, :]
    return np.where(np.abs(u) < half, 0.0, -np.inf)


def test_plate_on_an_obstacle_meets_its_optimality_conditions():
    grid = PlateGrid.covering(30.0, 10.0, 0.5)
    envelope = _strip(grid, 8.0) + 0.3 * np.sin(grid.v)[None, :]  # a bumpy support
    bending, load = 10.0, 0.2
    w = drape_plate(envelope, grid, bending, load)
    supported = np.isfinite(envelope)
    assert (w[supported] >= envelope[supported] - 1e-9).all()  # never into the support
    reaction = (plate_stiffness(grid, bending) @ w.ravel() + load * grid.h**2).reshape(w.shape)
    touching = supported & (np.abs(w - envelope) < 1e-9)
    scale = load * grid.h**2
    assert (reaction[touching] > -1e-6 * scale).all()  # the support only pushes
    assert np.abs(reaction[~touching]).max() < 1e-4 * scale  # elsewhere the plate is in equilibrium
    flat = drape_plate(np.zeros((grid.nu, grid.nv)), grid, bending, load)
    assert np.abs(flat).max() < 1e-9  # fully supported: it lies on the support


def test_simply_supported_strip_sags_as_the_beam_formula():
    """A strip resting on two line supports at its ends (span S) sags 5·q·S⁴/(384·D) at midspan (Euler–
    Bernoulli, cylindrical bending: the plate energy reduces to the beam's)."""
    grid = PlateGrid(u0=-10.0, v0=-2.0, h=0.25, nu=81, nv=17)
    envelope = np.full((grid.nu, grid.nv), -np.inf)
    envelope[[0, -1], :] = 0.0
    bending, load, span = 400.0, 0.05, 20.0
    w = drape_plate(envelope, grid, bending, load)
    assert -w[grid.nu // 2].mean() == pytest.approx(5 * load * span**4 / (384 * bending), rel=0.01)


def test_overhang_droops_in_proportion_to_load_over_stiffness():
    """Linear plate: with the same contact set, the overhang's droop scales as q/D (doubling E halves it),
    and is at least the clamped cantilever's q·L⁴/(8·D) (a one-sided support holds it less than a clamp)."""
    grid = PlateGrid.covering(40.0, 6.0, 0.5)
    envelope = _strip(grid, 10.0)
    load, overhang = 0.05, 10.0
    tips = []
    for bending in (400.0, 800.0):
        w = drape_plate(envelope, grid, bending, load)
        tips.append(-w[[0, -1]].mean())
    assert tips[0] > 0 and tips[1] / tips[0] == pytest.approx(0.5, rel=0.02)
    cantilever = load * overhang**4 / (8 * 400.0)
    assert cantilever < tips[0] < 10 * cantilever


def test_slab_rests_on_the_block_and_droops_over_its_ends(block):
    aggregate, mesh = block
    droops = []
    for modulus in (8.0, 80.0):
        fish = drape.call(aggregate=aggregate, young_modulus=modulus, clearance=0.05)
        slab = fish.element_mesh(0)
        assert fish.libraries[0].kind == "salmon" and len(fish.placement) == 1
        assert trimesh.Trimesh(slab.vertices, slab.faces).is_watertight
        distance = igl.signed_distance(slab.vertices, np.asarray(mesh.vertices), np.asarray(mesh.faces))[0]
        assert distance.min() > 0.0 and distance.min() < 0.3  # on the rice, not in it
        top = slab.vertices[np.abs(slab.vertices[:, 0]) < 5.0, 2].max()
        ends = slab.vertices[np.abs(slab.vertices[:, 0]) > 28.0, 2].max()
        droops.append(top - ends)
        midline = slab.vertices[np.abs(slab.vertices[:, 1]) < 0.5]
        assert np.ptp(midline[:, 0]) < 64.0 * 1.01  # bent, not stretched: no longer than the slab
    assert droops[0] > droops[1] > 0 and droops[0] > 5.0  # a soft slab follows the rounded ends


def test_fat_lines_and_bad_input(block):
    aggregate, _ = block
    salmon = drape.call(aggregate=aggregate).element_mesh(0)
    tuna = drape.call(aggregate=aggregate, kind="tuna").element_mesh(0)
    # thin lines: a twelfth of a 6 mm flake (0.5 mm on average), a few faces wide (the mesh under half of it)
    assert 0.05 < salmon.parts.mean() < 0.2 and 0 < tuna.parts.mean() < salmon.parts.mean()
    edges = np.linalg.norm(salmon.vertices[salmon.faces] - np.roll(salmon.vertices[salmon.faces], 1, axis=1), axis=2)
    assert np.median(edges) <= 0.4  # 0.53 at the plate's 0.5 mm cell
    with pytest.raises(ValueError, match="length ≥ width > thickness"):
        drape.call(aggregate=aggregate, size=(20.0, 30.0, 5.0))
    with pytest.raises(ValueError, match="nothing under it"):
        drape.call(aggregate=aggregate, offset=(200.0, 0.0))


def test_fat_lines_are_thin_parallel_chevrons():
    """One fold of McGee's W across a nigiri's slice: each line a chevron, straight arms running back the
    chevron's depth over half the width from the apex, and every line the same shape a flake further on (lines
    that looped like contour lines read as a drawing, not salmon: issue 48)."""
    from nodes.shapes.plate_drape import CHEVRON_APEX, CHEVRON_DRIFT, fat_lines

    width, chevron, spacing = 24.0, 4.0, 6.0
    u = np.arange(-20.0, 20.0, 0.01)
    apex = CHEVRON_APEX * width
    rows = apex + np.array([-12.0, -9.0, -6.0, 0.0, 6.0, 9.0, 12.0]) * 0.5  # apex ± up to half the half-width
    crossings = []
    for v in rows:
        fat = fat_lines(np.c_[u, np.full_like(u, v)], width, spacing, 0.5, 0.0, chevron)
        starts = u[1:][np.diff(fat) > 0]  # where each line begins along this row
        crossings.append(starts[:5])
    crossings = np.array(crossings)
    gaps = np.diff(crossings, axis=1)
    assert np.abs(gaps - spacing).max() < 2.5 * CHEVRON_DRIFT  # parallel: a flake apart in every row
    first = crossings[:, 0]
    depth = first[3] - 0.5 * (first[0] + first[-1])  # the apex lies the chevron's depth × ½ ahead of the arms
    assert 0.7 * chevron / 2 < depth < 1.3 * chevron / 2
    arm = first[:4]  # straight arms: equal steps for equal steps across (1.5, 1.5, 3 mm)
    assert abs((arm[1] - arm[0]) - 0.5 * (arm[3] - arm[1])) < 2.0 * CHEVRON_DRIFT


def test_fat_lines_swell_and_thin_a_little_along_their_length():
    """A myoseptum meets the knife at an angle that changes along it: a line is broader in places, yet stays
    thin, its width within a factor 2 (at 2.5 and more the swellings looped like contour lines, issue 48)."""
    from nodes.shapes.plate_drape import fat_lines

    width = 27.0
    u = np.arange(-3.0, 3.0, 0.002)  # one line crosses each row near u = 0 (no chevron)
    widths = []
    for v in np.linspace(-12.0, 12.0, 25):
        fat = fat_lines(np.c_[u, np.full_like(u, v)], width, 100.0, 0.4, 0.0, 0.0)
        widths.append(fat.sum() * 0.002)
    widths = np.array(widths)
    assert widths.min() > 0.2 and widths.max() < 0.6  # thin throughout: ≈ 0.3–0.5 mm at a 0.4 mm mean
    assert 1.3 * widths.min() < widths.max() < 2.0 * widths.min()


def test_flakes_stand_proud_of_the_fat_lines(block):
    """The slab's top rises in a low dome over each flake and falls to its flat top at each fat line, where the
    wet film catches the key as a glint a flake; the bottom, resting on the rice, stays flat."""
    from nodes.shapes.plate_drape import FLAKE_RELIEF, flake_relief

    thickness, width, spacing = 5.0, 27.0, 6.0
    u = np.arange(-20.0, 20.0, 0.05)
    top = np.c_[u, np.zeros_like(u), np.full_like(u, 0.5 * thickness)]
    fat = importlib.import_module("nodes.shapes.drape").FAT_LINES["salmon"]
    rise = flake_relief(top, thickness, width, spacing, fat[2], fat[3])
    assert rise.max() > 0.95 * FLAKE_RELIEF and rise.min() < 0.05 * FLAKE_RELIEF  # domes between lines
    bottom = top * [1.0, 1.0, -1.0]
    assert not flake_relief(bottom, thickness, width, spacing, fat[2], fat[3]).any()
    aggregate, _ = block
    slab = drape.call(aggregate=aggregate).element_mesh(0)
    assert trimesh.Trimesh(slab.vertices, slab.faces).is_watertight
