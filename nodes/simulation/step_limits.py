"""How long a step the solver can take: the solves a substep splits into for a fast particle (a CFL condition) and
the refusal of a step in which gravity alone sinks resting stacks past what the iterations hold. numpy only, so
``check`` weighs a recipe's substeps with the same rule before any work (``xpbd._cost``)."""

import numpy as np

from .settings import SolverSettings

# the longest travel of a particle in one solve, in radii: a substep in which the fastest awake particle would
# travel further runs as ceil(travel / MAX_TRAVEL) solves, up to ceil(clamp / MAX_TRAVEL) (``solve_pieces``);
# with one solve at clamp 2, 47 of 200 fast particles tunnelled through a 0.8 mm bowl wall, at 4 all 200
MAX_TRAVEL = 1.0


# a resting stack sinks ≈ SINK·g·h²/iterations into its support every substep before the solve carries
# the weight (stack of two cubes, 30 frames, r = 1 mm: max penetration / (g·h²/r) = 2.6, 1.8, 0.7, 0.2
# at 1, 2, 4, 8 iterations, with g·h² from 0.17 to 0.68 r; 4/iterations bounds all of them)
SINK = 4.0
HOLD = 1.0  # resting overlap, radii, beyond which a stack has collapsed (centres past the contact): refused


def most_pieces(settings: SolverSettings) -> int:
    """The most solves a substep splits into: ceil(speed_clamp / MAX_TRAVEL)."""
    return max(1, int(np.ceil(settings.speed_clamp / MAX_TRAVEL - 1e-12)))


def solve_pieces(travel: float, most: int) -> int:
    """Solves for a substep in which the fastest awake particle would travel ``travel`` radii (|v|·h + g·h²): as
    many as keep each solve's travel ≤ MAX_TRAVEL, at most ``most`` (beyond, the speed clamp holds it). A CFL
    condition: a fall keeps its speed at any substep count (at 10 substeps one solve caps a 1 mm particle at
    0.6 m/s, the speed of a 18 mm fall), and the solver pays for it only while something moves that fast."""
    return int(min(most, max(1, np.ceil(travel / MAX_TRAVEL - 1e-9))))


def check_gravity_step(settings: SolverSettings, pieces: int, r_min: float, r_typical: float) -> None:
    """Refuse a step in which gravity alone sinks resting particles deeper than the solver holds:
    g·h² ≤ HOLD·iterations/SINK·r, r the median radius (the particles that carry a pile; stacks then
    rest within HOLD radii: 2 substeps × 2 iterations of 1/60 s let a stack of 1 mm particles
    collapse to 1.2 r, issue 11), and g·h² ≤ clamp·r_min (the speed clamp would hold the smallest
    particle to less than gravity's step). ``pieces``: solves per substep. Raises ValueError naming
    the substeps (and iterations) that would do."""
    s = settings
    h = s.h / pieces
    step = s.gravity * h * h  # mm
    hold = HOLD * s.iterations / SINK * r_typical
    clamped = min(MAX_TRAVEL, s.speed_clamp / pieces) * r_min
    if step <= min(hold, clamped):
        return
    need = int(np.ceil(s.dt / pieces * np.sqrt(s.gravity / min(hold, clamped)) - 1e-9))
    options = [f"substeps ≥ {need}"]
    iterations = int(np.ceil(SINK * step / (HOLD * r_typical) - 1e-9))
    if step <= clamped and iterations <= 64:
        options.append(f"iterations ≥ {iterations}")
    why = (
        f"the speed clamp ({clamped / r_min:.3g} r per solve: {clamped:.3g} mm)"
        if clamped < hold
        else f"what {s.iterations} iterations hold ({hold:.3g} mm: ≈ {SINK:g}·g·h²/iterations of overlap, "
        f"at most {HOLD:g} r of the median r = {r_typical:.3g} mm)"
    )
    raise ValueError(
        f"substeps: dt / substeps = {s.h:.3g} s lets gravity alone move a particle g·h² = {step:.3g} mm per "
        f"substep, more than {why}: resting stacks would sink "
        f"into each other; use {' or '.join(options)}, or a shorter dt"
    )
