"""The validation suite's quick figures (issue 24, ``benchmarks/validation.py``): heaps of spheres and of
rice-like grains under the default (anchored) friction hold their angle and rest; friction loosens random
packing. Each fails on a solver that ignores friction (heap flat, packing unchanged)."""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "validation.py"


@pytest.fixture(scope="module")
def validation():
    spec = importlib.util.spec_from_file_location("validation_benchmark", PATH)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass looks its module up
    spec.loader.exec_module(module)
    return module


def test_heap_angle_reads_a_cone(validation):
    """The metric: points filling a 30° cone (radius 20 mm) read 30° within 2°."""
    rng = np.random.default_rng(0)
    p = rng.uniform([-20, -20, 0], [20, 20, 20 * np.tan(np.radians(30))], (20000, 3))
    cone = p[p[:, 2] < (20 - np.hypot(p[:, 0], p[:, 1])) * np.tan(np.radians(30))]
    assert abs(validation.heap_angle(cone) - 30.0) < 2.0


def test_anchored_sphere_heap_holds_its_angle_and_rests(validation):
    """600 spheres dropped on the ground at μs 0.6 (quick case): measured 30.1° at 2.5 s and at 5 s, 28.3° at
    4× the substeps (the substep rule: 13.7° creeping to 6.2°, 25.4° at 4× the substeps); frictionless they
    spread flat (0.0°). Issue 24: ≤ 3° from 2.5 s on and from the default substeps to 4× them."""
    (early, late), _ = validation.sphere_heap(600, 0.6, True, frames=(150, 300))
    assert 26.0 < early < 34.0
    assert abs(late - early) < 1.0
    (fine,), _ = validation.sphere_heap(600, 0.6, True, frames=(150,), substeps=40)
    assert abs(fine - early) < 3.0
    (flat,), _ = validation.sphere_heap(600, 0.0, True, frames=(150,))
    assert flat < 3.0


def test_friction_loosens_random_packing(validation):
    """1,500 spheres settled in a box (quick case): frictionless φ 0.667, μ 0.3 (anchored) 0.654 — against
    0.639 and 0.593 (Agnolin & Roux 2007): too dense by 0.03–0.06, but friction loosens it as it should."""
    dense, _ = validation.packing_fraction(1500, 0.0, True)
    loose, _ = validation.packing_fraction(1500, 0.3, True)
    assert 0.645 < dense < 0.69
    assert 0.625 < loose < 0.665
    assert dense - loose > 0.01


def test_rice_heap_rests(validation):
    """300 rice-like grains poured at the xpbd node's defaults (quick case; measured H/R 24.3° at 2.5 s and 24.2° at
    7 s; at speed clamp 1, 36.5° and 36.5°): issue 24 asks for ≤ 3° of change. The anchored rule without the
    substep's normal load crept 28.7° → 27.1° (→ 25.1° at 7 s), the substep rule spread to 12.6° by 5 s, frictionless
    1.7°."""
    (early, late), _ = validation.rice_heap(300, True, frames=(150, 300))
    assert abs(late[1] - early[1]) <= 3.0
    ((_, flat),), _ = validation.rice_heap(300, True, frames=(150,), friction=0.0)
    assert flat < 5.0


@pytest.mark.xfail(
    strict=True,
    reason="issue 46: at the default speed clamp 4 the stream lands at its fall speed and stands at H/R 24.3° "
    "(21.3° at 40 substeps); the 36.5° it stood at with clamp 1 came from the clamp braking its landing at 10 "
    "substeps only (docs/validation.md, 'Where the solver misses')",
)
def test_rice_heap_stands_at_its_angle_of_repose(validation):
    """Issue 24 asks for 30–45° (rough rice piles at 29.6–36.9°, doi:10.13031/aea.13156; paddy at 35.7–44.4°)."""
    ((_, hr),), _ = validation.rice_heap(300, True, frames=(150,))
    assert 30.0 <= hr <= 45.0


def test_janssen_fit_recovers_the_saturation(validation):
    """The fit: points on M_sat(1 − e^(−M/M_sat)) with M_sat = 12 g give back 12 g."""
    m = np.array([4.0, 8.0, 16.0, 24.0])
    assert abs(validation.janssen_fit(m, 12.0 * (1 - np.exp(-m / 12.0))) - 12.0) < 1e-3


def test_silo_walls_carry_part_of_the_weight(validation):
    """The Janssen effect (quick case): 600 spheres (15 g) in a 12 mm silo with walls at μ 0.6: the floor carries
    M_sat(1 − e^(−M/M_sat)) by Janssen (1895) with λ = D/(4 μ K) = 10 mm (Jaky's K = 0.5 at the sphere heap's 30°)
    and the bed's ρ_b A = 0.447 g/mm: 4.3 g = 0.29 M (measured 5.0 g = 0.33 M; 0.66 M while the walls took
    each particle's penetration alone as friction's load) and the walls' friction the rest; frictionless, the floor
    carries it all (0.999 M). Fails on a solver that ignores friction (ratio 1) or a gauge that misses forces."""
    deep = validation.silo_fill(600, 0.6)
    assert 0.2 < deep["apparent"] / deep["M"] < 0.4
    assert abs(deep["apparent"] + deep["walls"] - deep["M"]) < 0.03 * deep["M"]
    smooth = validation.silo_fill(300, 0.0)
    assert abs(smooth["apparent"] / smooth["M"] - 1.0) < 0.02
    assert smooth["walls"] == 0.0


def test_xpbd_grain_is_rigid_across_its_thickness(validation):
    """The squeezed grain, (a′) (quick case), rigid contacts (squeeze_strain 0): three library grains under a plate;
    0.2 N each strains them 1.5 % (the contacts' overlap; Tomita: 25 %), 1 N 4.3 %: 8 rigid spheres in one plane
    cannot get thinner. Fails if the load is lost (no strain at 1 N) or the grains give way like cooked rice (the
    compliant contacts' part: test_compliant_contacts.py)."""
    rest = validation.squeeze_xpbd(0.001, squeeze_strain=0.0)
    assert 0.7 * rest["thickness"] < rest["gap"] <= rest["thickness"]  # the plate rests on the grains
    light = 1 - validation.squeeze_xpbd(0.2, squeeze_strain=0.0)["gap"] / rest["gap"]
    heavy = 1 - validation.squeeze_xpbd(1.0, squeeze_strain=0.0)["gap"] / rest["gap"]
    assert -0.01 < light < 0.05
    assert 0.02 < heavy < 0.08


def test_two_layer_grain_flattens_under_a_plate_and_springs_back(validation):
    """The squeezed grain, (c): with particle_layers 2 (16 particles, 8 iterations, 1000 N/m, rigid contacts) the grain
    flattens 5.1 % under 0.2 N and keeps 1.2 % of it 1/6 s after the plate is lifted, where one layer of as many
    particles does not flatten at all (its spheres lie in one plane). At 100 N/m the plate squeezes the grain out
    from under it: sliding friction takes μk·load over a substep, not per iteration, and it was 8 iterations'
    friction that held so soft a grain together. Fails if the layered cover falls back to one plane (the grain
    rigid again) or the grain stays crushed."""
    settings = dict(frames=20, after=10, iterations=8, stiffness=1000.0, squeeze_strain=0.0)  # rigid contacts
    layered = validation.squeeze_xpbd(0.2, particles=16, layers=2, **settings)
    flat = validation.squeeze_xpbd(0.2, particles=16, layers=1, **settings)
    assert layered["escaped"] == 0
    assert 1 - layered["loaded"] / layered["thickness"] > 0.04
    assert 1 - layered["after"] / layered["thickness"] < 0.03
    assert abs(1 - flat["loaded"] / flat["thickness"]) < 0.01


def test_elastic_grain_strains_linearly_and_does_not_tear_in_compression(validation):
    """The squeezed grain, (b): the elastic body at the fitted stiffness strains 25 % at 0.2 N (measured 25.1 %) and
    12.5 % at 0.1 N (linear), 50 % at 0.4 N, and never tears under compression (longest edge 2.08× at 0.8 N, the
    vertex rule needs 3×)."""
    full = validation.squeeze_body(0.2)
    half = validation.squeeze_body(0.1)
    assert 0.22 < full["strain"] < 0.28
    assert 0.45 < half["strain"] / full["strain"] < 0.55
    crushed = validation.squeeze_body(0.8)
    assert crushed["strain"] > 0.9
    assert crushed["tears"] == 0 and crushed["stretch"] < 3.0


def test_ellipsoid_fraction_reads_a_lattice(validation):
    """The packing metric: ellipsoids 1.25 × 1 × 0.8 turned so that body x, y, z lie along world y, z, x, on the
    lattice their turned boxes tile (1.6 × 2.5 × 2), fill π/6 of any box, as spheres in a cubic lattice do."""
    axes = np.array([1.25, 1.0, 0.8])
    turn = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # columns: where body x, y, z point
    k = np.stack(np.meshgrid(np.arange(10), np.arange(8), np.arange(8), indexing="ij"), -1).reshape(-1, 3)
    centres = k * [1.6, 2.5, 2.0]
    turns = np.tile(turn, (len(centres), 1, 1))
    phi = validation.ellipsoid_fraction(centres, turns, axes, [1.6, 2.5, 2.0], [11.2, 12.5, 10.0], 0.1)
    assert abs(phi - np.pi / 6) < 0.01


@pytest.mark.slow
def test_elongated_clusters_pack_denser_and_their_ellipsoids_overlap(validation):
    """Ellipsoid packing (``--ellipsoids`` quick case, settled 1.5 s instead of 2.5 s: ≈ 17 s): the particles of
    1.25:1:0.8 grains pack denser than those of round ones (measured 0.786 against 0.711; 0.791 against 0.715 at
    2.5 s; Donev et al. 2004: 0.735 against 0.64), and the drawn ellipsoids, which their 8 particles fill to 79 %,
    read a φ no hard packing reaches (0.915)."""
    round_drawn, round_solid, _ = validation.ellipsoid_packing(1.0, 506, frames=90)
    long_drawn, long_solid, _ = validation.ellipsoid_packing(1.25, 608, frames=90)
    assert 0.69 < round_solid < 0.74 and 0.76 < long_solid < 0.82
    assert long_solid - round_solid > 0.04
    assert long_drawn > 0.88 and round_drawn > round_solid
