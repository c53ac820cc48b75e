"""The docs' measured tables, rendered from ``benchmarks/measured/*.jsonl``.

A measurement is one JSON line: what was measured, the command, its values, the unit, the machine's load and
date, and the machine. A doc asks for a table between two marker comments::

    <!-- table: scene_times -->
    (generated)
    <!-- /table -->

    python tools/measured_tables.py            # rewrite every table in README.md and docs/*.md
    python tools/measured_tables.py --check    # exit 1 if a doc differs from its data (tests/docs runs this)

To change a figure, re-run its command and replace its line in the JSONL file, then run this tool; a number
edited by hand in a doc fails the check.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MEASURED = ROOT / "benchmarks" / "measured"
MARKER = re.compile(r"(<!-- table: (?P<name>[a-z0-9_]+) -->\n)(?P<body>.*?)(<!-- /table -->)", re.S)


def records(name: str) -> list[dict]:
    """The records of one JSONL file of ``benchmarks/measured/``."""
    lines = (MEASURED / name).read_text().splitlines()
    return [json.loads(line) for line in lines if line.strip()]


def _mass_scaling(r: dict) -> tuple[str, str]:
    """(what ours does, what physics says) of a ``mass_scaling.jsonl`` row: a fall, a rise, or the kernel families."""
    v = r["values"]
    if "fall" in v:
        return f"falls {number(v['fall'])} mm", f"½·g·t² = {number(v['free_fall'])} mm: the pair adds no momentum"
    if "rise" in v:
        return f"rises {number(v['rise'])} mm; {v['outside']} of {v['grains']} outside", "a pile settles: no rise"
    added = "; ".join(f"{name} {value:+.3f}" for name, value in v.items() if abs(value) >= 0.0005)
    return added + " mm a frame", "contacts between grains add no height; gravity and the walls do"


def number(value, digits: int | None = None) -> str:
    """A figure as the docs print it: a thousands separator, the decimals it was recorded with (or ``digits``),
    "—" for none."""
    if value is None or value == "":
        return "—"
    if isinstance(value, str):
        return value
    if isinstance(value, int) and not isinstance(value, bool):
        return f"{value:,}"
    return f"{value:,}" if digits is None else f"{value:,.{digits}f}"


def value(key: str, digits: int | None = None):
    return lambda r: number(r["values"].get(key), digits)


def field(key: str, digits: int | None = None):
    return lambda r: number(r.get(key), digits)


def code(key: str):
    return lambda r: f"`{r[key]}`"


def pair(*keys: str, digits: int | None = None):
    return lambda r: " / ".join(number(r["values"].get(k), digits) for k in keys)


def listed(key: str, digits: int | None = None):
    return lambda r: " / ".join(number(v, digits) for v in r["values"][key])


def ratio(a: str, b: str, digits: int = 2):
    return lambda r: f"{r['values'][a] / r['values'][b]:.{digits}f}×"


# name: (file, record filter, [(column header, cell)])
TABLES = {
    # the README's first lines: what a first hour meets, each row a record marked "readme" (its label)
    "first_hour": (
        ("compile.jsonl", "scenes.jsonl", "main_job.jsonl"),
        lambda r: "readme" in r,
        [
            ("the main job", field("readme")),
            ("wall s", value("wall")),
            ("CPU s", lambda r: number(r["values"].get("cpu", r["values"].get("nodes_cpu")))),
            ("load", field("load")),
        ],
    ),
    "mass_scaling": (
        "mass_scaling.jsonl",
        None,
        [
            ("set-up", field("what")),
            ("substeps", field("substeps")),
            ("ours", lambda r: _mass_scaling(r)[0]),
            ("physics says", lambda r: _mass_scaling(r)[1]),
        ],
    ),
    "lift_apart": (
        "lift_apart.jsonl",
        None,
        [
            ("egg_apart.overlap", field("overlap")),
            ("eggs outside the bowl, seeds 3 / 4 / 5", listed("outside")),
            ("eggs", listed("eggs")),
            ("eggs lifted", listed("lifted")),
            ("load", field("load")),
        ],
    ),
    "scene_times": (
        "scenes.jsonl",
        None,
        [
            ("recipe", code("recipe")),
            ("elements", field("elements")),
            ("preview", field("preview")),
            ("wall s", lambda r: f"**{number(r['values']['wall'])}**"),
            ("nodes' CPU s", value("nodes_cpu")),
            ("slowest nodes, wall s (CPU s)", field("slowest_nodes")),
        ],
    ),
    "speed_levers": (
        "speed_levers.jsonl",
        None,
        [
            ("recipe", code("recipe")),
            ("nodes", field("nodes")),
            ("what changed", field("lever")),
            ("CPU s, with the lever", value("after")),
            ("CPU s, without", value("before")),
            ("with / without", ratio("after", "before")),
            ("outputs", field("outputs")),
        ],
    ),
    "main_job": (
        "main_job.jsonl",
        None,
        [
            ("run", field("what")),
            ("wall s", value("wall")),
            ("CPU s", lambda r: number(r["values"].get("cpu", r["values"].get("compile")))),
            ("command", code("command")),
        ],
    ),
    "test_suite": (
        "test_suite.jsonl",
        None,
        [
            ("run", field("what")),
            ("tests", value("tests")),
            ("wall s", value("wall")),
            ("CPU s", value("cpu")),
            ("command", code("command")),
        ],
    ),
    "first_run": (
        "compile.jsonl",
        lambda r: "kernel" not in r,
        [
            ("run", field("what")),
            ("wall s", value("wall")),
            ("CPU s", value("cpu")),
            ("kernels compiled", value("compiled")),
            ("command", code("command")),
        ],
    ),
    "compile_kernels": (
        "compile.jsonl",
        lambda r: "kernel" in r,
        [
            ("kernel", code("kernel")),
            ("argument types", field("arguments")),
            ("compile s", value("compile", 2)),
            ("CPU s", value("cpu", 2)),
        ],
    ),
    "xpbd_newton": (
        "xpbd_newton.jsonl",
        lambda r: "settings" not in r and "side" not in r,  # equal substeps
        [
            ("particles", field("particles")),
            ("threads, ours / Newton", lambda r: "1 / 1" if "one thread each" in r["what"] else "2 / 1"),
            ("unit", field("unit")),
            ("ours", value("ours")),
            ("Newton", value("newton")),
            ("ratio", ratio("ours", "newton")),
        ],
    ),
    # each side at the cheapest settings at which its pile converges and rests (bench_xpbd_newton.py --equal-piles)
    "xpbd_newton_piles": (
        "xpbd_newton.jsonl",
        lambda r: "settings" in r,
        [
            ("particles", field("particles")),
            ("substeps × iterations, ours / Newton", lambda r: " / ".join(r["settings"].values())),
            ("packing at 1.5 s, ours / Newton", pair("packing_ours", "packing_newton", digits=3)),
            ("mean speed at 1.5 s, ours / Newton (mm/s)", pair("speed_ours", "speed_newton", digits=2)),
            ("CPU s per simulated s, ours / Newton", pair("ours", "newton", digits=2)),
            ("ratio", lambda r: f"**{r['values']['newton'] / r['values']['ours']:.1f}×**"),
        ],
    ),
    # one side's pile at one setting (bench_xpbd_newton.py --pile): where it converges and rests
    "xpbd_newton_tries": (
        "xpbd_newton.jsonl",
        lambda r: "side" in r,
        [
            ("side", field("side")),
            ("particles", field("particles")),
            ("μ", field("mu")),
            ("substeps × iterations", lambda r: f"{r['substeps']} × {r['iterations']}"),
            ("packing at 1 s / at the end", listed("packing", 3)),
            ("mean speed at 1 s / at the end (mm/s)", listed("speed", 1)),
            ("end (s)", value("end")),
        ],
    ),
    "xpbd_profile": (
        "xpbd_profile.jsonl",
        None,
        [
            ("build", field("build")),
            ("kernel", code("kernel")),
            ("CPU ms per substep", value("ms", 3)),
            ("calls per substep", value("calls", 0)),
        ],
    ),
    "physics_defaults": (
        "physics_defaults.jsonl",
        None,
        [
            ("case", field("case")),
            ("set-up", field("setup")),
            ("substeps", field("substeps")),
            ("ours", field("ours")),
            ("published", field("published")),
        ],
    ),
    "heap_levers": (
        "heap_levers.jsonl",
        None,
        [
            ("changed from the defaults", field("lever")),
            (
                "poured stream: atan H/R at 10 / 40 substeps (°)",
                lambda r: f"{r['values']['stream_10']} / {r['values']['stream_40']}",
            ),
            (
                "dropped ball: atan H/R at 10 / 40 substeps (°)",
                lambda r: f"{r['values']['ball_10']} / {r['values']['ball_40']}",
            ),
            (
                "stream: surface slope at 10 / 40 (°)",
                lambda r: f"{r['values']['stream_10_surface']} / {r['values']['stream_40_surface']}",
            ),
            ("s (four heaps)", value("seconds")),
        ],
    ),
    "granular_convergence": (
        "granular_convergence.jsonl",
        None,
        [
            ("substeps", lambda r: f"**{r['substeps']}**" if r["substeps"] == 10 else str(r["substeps"])),
            ("poured heap: surface slope at 7 s, seeds 0 / 1 (°)", listed("surface_7")),
            ("poured heap: atan H/R at 7 s, seeds 0 / 1 (°)", listed("hr_7")),
            ("heap s (each)", value("heap_seconds")),
            ("grain across its length holds to (°)", value("holds")),
            ("plane s (21 tilts)", value("plane_seconds")),
        ],
    ),
    "funnel_heap": (
        "funnel_heap.jsonl",
        None,
        [
            ("substeps", lambda r: f"**{r['substeps']}**" if r["substeps"] == 10 else str(r["substeps"])),
            ("surface slope at 3 s, seeds 0 / 1 (°)", listed("surface")),
            ("atan H/R (°)", listed("hr")),
            ("grains in the heap", listed("grains")),
            ("heap top (mm; outlet at 15)", listed("top_mm")),
            ("s (each)", value("seconds")),
        ],
    ),
    "heap_mechanism": (
        "heap_mechanism.jsonl",
        None,
        [
            ("ball (grains)", field("grains")),
            ("substeps × iterations", lambda r: f"{r['substeps']} × {r['iterations']}"),
            (
                "atan H/R at 0.1 s / 0.3 s / end, seed 0 (°)",
                lambda r: " / ".join(number(r["values"][k][0]) for k in ("hr_0_1", "hr_0_3", "hr")),
            ),
            ("atan H/R at the end, per seed (°)", listed("hr")),
            ("surface slope at the end, per seed (°)", listed("surface")),
            ("grain–grain contacts per grain", listed("contacts_per_grain")),
            ("contacts sticking", listed("sticking")),
            ("largest overlap, last 10 frames (r)", listed("penetration")),
            ("s (each)", value("seconds")),
        ],
    ),
    "heap_creep": (
        "heap_creep.jsonl",
        None,
        [
            ("ball (grains)", field("grains")),
            ("substeps", field("substeps")),
            ("atan H/R at 2.5 s / 7 s (°)", pair("hr_2_5", "hr_7")),
            ("grains moving > 0.2 mm from 2.5 s to 7 s, all / on the ground", pair("creeping", "creeping_on_ground")),
            (
                "their move, median / p95 / max (mm)",
                lambda r: " / ".join(number(r["values"][k]) for k in ("median_mm", "p95_mm", "max_mm")),
            ),
            ("s", value("seconds")),
        ],
    ),
    "pass_overlap": (
        "pass_overlap.jsonl",
        None,
        [
            ("substeps (2 iterations)", field("substeps")),
            ("after pre-stabilisation (mm)", value("pre-stabilisation")),
            ("after the prediction (mm)", value("predicted")),
            ("after a contact sweep (mm)", value("sweep")),
            ("after shape matching (mm)", value("shape matching")),
            ("after the walls (mm)", value("walls")),
        ],
    ),
    "rigid_contacts": (
        "rigid_contacts.jsonl",
        lambda r: r["case"] == "contact response",
        [
            ("contact response", field("response")),
            ("substeps × iterations", lambda r: f"{r['substeps']} × {r['iterations']}"),
            ("ball, 890: atan H/R at 0.3 s / 1 s (°)", pair("ball_hr_0_3", "ball_hr_1")),
            ("its surface slope at 1 s (°)", value("ball_surface_1")),
            ("grain–grain contacts per grain", value("contacts_per_grain")),
            ("contacts sticking", value("sticking")),
            ("largest overlap, last 10 frames (r)", value("penetration")),
            ("stream, 300: atan H/R / surface slope at 2.5 s (°)", pair("stream_hr_2_5", "stream_surface_2_5")),
            ("s, ball / stream", pair("ball_seconds", "stream_seconds")),
        ],
    ),
    "rigid_pass_overlap": (
        "rigid_contacts.jsonl",
        lambda r: r["case"] == "overlap through a pass",
        [
            ("substeps (2 iterations), rigid grains", field("substeps")),
            ("after pre-stabilisation (mm)", value("pre-stabilisation")),
            ("after the prediction (mm)", value("predicted")),
            ("after a contact sweep (mm)", value("sweep")),
            ("after shape matching (mm)", value("shape matching")),
            ("after the walls (mm)", value("walls")),
        ],
    ),
    "solver_passes": (
        "solver_passes.jsonl",
        lambda r: r["case"] == "solver passes",
        [
            ("substeps × iterations", lambda r: f"{r['substeps']} × {r['iterations']}"),
            ("passes per frame", lambda r: str(r["substeps"] * r["iterations"])),
            ("funnel heap: surface slope, seeds 0 / 1 (°)", listed("surface")),
            ("atan H/R (°)", listed("hr")),
            ("grain along the plane holds to (°)", value("holds_along")),
            ("across (°)", value("holds_across")),
            ("heap s (each)", value("seconds")),
        ],
    ),
    "stream_landing": (
        "solver_passes.jsonl",
        lambda r: r["case"] == "stream landing",
        [
            ("substeps", field("substeps")),
            ("speed clamp (radii per substep)", field("speed_clamp")),
            ("surface slope at 2.5 s (°)", value("surface_2_5")),
            ("atan H/R at 2.5 s (°)", value("hr_2_5")),
            ("s", value("seconds")),
        ],
    ),
    "validation_cases": (
        "validation.jsonl",
        None,
        [
            ("case", field("what")),
            ("set-up", field("setup")),
            ("reference (source)", field("reference")),
            ("ours", field("ours")),
            ("error", field("error")),
            ("knobs", field("knobs")),
            ("s", value("seconds")),
        ],
    ),
    "compliant_contacts": (
        "compliant_contacts.jsonl",
        None,
        [
            ("contacts, plate", field("what")),
            ("knobs", field("knobs")),
            (
                "plate strain at 0.05 / 0.2 / 1 N",
                lambda r: " / ".join(f"{v * 100:.1f} %" for v in r["values"]["strain"].values()),
            ),
            ("grains squeezed out", value("escaped")),
            ("left 0.5 s after the lift", lambda r: f"{r['values']['left_after_lift'] * 100:.1f} %"),
            ("10 mm drop: rebound mm", value("rebound")),
            ("s", value("seconds")),
        ],
    ),
    "compliant_heaps": (
        "compliant_heaps.jsonl",
        None,
        [
            ("heap, compliant contacts (squeeze_strain 25)", field("what")),
            ("substeps", field("substeps")),
            ("ours", field("ours")),
            ("s", value("seconds")),
        ],
    ),
    "compliant_main_job": (
        "compliant_main_job.jsonl",
        None,
        [
            ("the main job (ikura don)", field("what")),
            ("wall s / CPU s, no node cache", pair("wall", "cpu")),
            ("overlap depth / length p95 / max", pair("overlap_p95", "overlap_max")),
            ("pairs deeper than 1 %", value("deep_pairs")),
            ("bumps median / p95", pair("bumps_median", "bumps_p95")),
            ("folds", value("folds")),
            ("watertight", value("watertight")),
        ],
    ),
    "squeeze_candidates": (
        "squeeze_candidates.jsonl",
        None,
        [
            ("layout", field("what")),
            ("knobs", field("knobs")),
            ("particles per grain", value("particles")),
            (
                "plate strain at 0.05 / 0.2 / 1 N",
                lambda r: " / ".join(f"{v * 100:.1f} %" for v in r["values"]["plate_strain"].values()),
            ),
            (
                "grains off the plate (0.05 / 0.2 / 1 N)",
                lambda r: " / ".join(map(str, r["values"]["escaped"].values())),
            ),
            ("grain flattened at 0.2 N", lambda r: f"{r['values']['flattening'] * 100:.1f} %"),
            ("left 0.5 s after the lift", lambda r: f"{r['values']['left_after_lift'] * 100:.1f} %"),
            (
                "stream heap H/R 2.5 s → 7 s",
                lambda r: f"{r['values']['hr_2_5']}° → {r['values']['hr_7']}°" if "hr_7" in r["values"] else "—",
            ),
            ("heap solver s", value("heap_seconds")),
        ],
    ),
    "silo_discharge": (
        "silo_discharge.jsonl",
        lambda r: r["what"] == "silo_discharge",
        [
            ("silo, mm (fill height)", lambda r: f"{r['silo_diameter_mm']:g} ({r['fill_height_mm']:g})"),
            ("hole D, mm", field("D_mm")),
            ("substeps", field("substeps")),
            ("damping", field("damping")),
            ("grains", field("grains")),
            ("bulk density, g/cm³", field("rho_b_g_per_cm3")),
            (
                "rate, grains/s",
                lambda r: (
                    number(r["rate_grains_per_s"])
                    + (f" (jammed: {r['discharged']:,} of {r['grains']:,} out)" if r.get("jam") else "")
                ),
            ),
            ("rate, g/s", field("rate_g_per_s")),
            (
                "first / second half of the window, grains/s",
                lambda r: f"{number(r['first_half'])} / {number(r['second_half'])}",
            ),
        ],
    ),
    "silo_fit": (
        "silo_discharge.jsonl",
        lambda r: r["what"] == "silo_discharge_fit",
        [
            ("holes", lambda r: ", ".join(f"{d:g}" for d in r["D_mm"]) + " mm"),
            ("n (k = 1.5)", field("n_k1.5")),
            ("n (k = 0)", field("n_k0")),
            ("k at n = 2.5", field("k_n2.5")),
            ("C at n = 2.5, that k", field("C_n2.5_kfit")),
            ("C at n = 2.5, k = 1.5", field("C_n2.5_k1.5")),
            ("published (Beverloo et al. 1961)", lambda r: "n = 2.5, k ≈ 1.3–2.9, C ≈ 0.55–0.65"),
        ],
    ),
    "roofline": (
        "roofline.jsonl",
        None,
        [
            ("what", field("what")),
            ("threads", field("threads")),
            ("value", lambda r: number(next(iter(r["values"].values())))),
            ("unit", field("unit")),
            ("load", field("load")),
        ],
    ),
    "skin_by_variety": (
        "skin.jsonl",
        None,
        [
            ("variety", field("variety")),
            ("water %", field("water_content")),
            ("grains", field("grains")),
            ("contacts per grain", field("contacts_per_grain", 2)),
            ("library", value("library", 3)),
            ("after the run", value("after_run", 3)),
            ("after deform_contacts, mean / p90", pair("after_contact_mean", "after_contact_p90", digits=3)),
        ],
    ),
    "contact_offset": (
        "contact_offset.jsonl",
        None,
        [
            ("`contact_offset` (radii)", field("contact_offset", 2)),
            ("skin 0 % / 15 % / 24 %", pair("skin_0", "skin_15", "skin_24", digits=3)),
            ("packing 0 % / 15 %", pair("packing_0", "packing_15", digits=2)),
            ("contacts per grain 0 % / 15 %", pair("contacts_0", "contacts_15")),
        ],
    ),
    "ice_whiteness": (
        "ice.jsonl",
        lambda r: "depth_128" in r["values"],
        [("ice", field("ice"))]
        + [(f"depth {d}", value(f"depth_{d}", 2)) for d in (10, 32, 64, 128, 256)]
        + [("render CPU s at 128", value("cpu_128"))],
    ),
    "ice_cost": (
        "ice.jsonl",
        lambda r: "cpu_ratio" in r["values"],
        [
            ("median CPU s, medium / thin diffuser", pair("cpu_a", "cpu_b")),
            ("CPU ratio", value("cpu_ratio", 2)),
            ("wall ratio", value("wall_ratio", 2)),
        ],
    ),
    "glints": (
        "glints.jsonl",
        None,
        [
            ("", field("quantity")),
            ("preview (pinhole + circle of confusion)", value("preview")),
            ("thin lens, 64 spp", value("lens_64spp")),
        ],
    ),
    "blender": (
        "blender.jsonl",
        None,
        [
            ("render", field("renderer")),
            ("egg", value("egg")),
            ("rice", value("rice")),
            ("rice between eggs", value("between")),
            ("R share between", value("r_share_between", 2)),
        ],
    ),
    "contact": (
        "contact.jsonl",
        None,
        [
            ("recipe", code("recipe")),
            ("elements", field("elements")),
            ("winding p95 / max (L)", value("winding_p95_max")),
            ("pseudonormal p95 / max (L)", value("pseudonormal_p95_max")),
            ("pairs > 1 %", value("pairs_over_1pct")),
            ("folded pairs / faces", value("folded_pairs")),
            ("volume error p95 / max (> 2 %)", value("volume_error")),
            ("contact CPU s", value("contact_cpu")),
            ("total s", value("total")),
        ],
    ),
    "slab_optics": (
        "slab_optics.jsonl",
        None,
        [
            ("slab", field("slab")),
            ("", field("quantity")),
            ("reference, path depth 64", value("reference_depth64")),
            ("reference, converged", value("reference")),
            ("preview (Mitsuba)", value("mitsuba")),
            ("Cycles, the add-on before", value("cycles_before")),
            ("Cycles, the add-on", value("cycles")),
        ],
    ),
    "rice_film": (
        "rice_film.jsonl",
        None,
        [
            ("measured", field("measured")),
            ("behind a refracting skin", value("skin")),
            ("behind the film", value("film")),
        ],
    ),
    "rice_sheen": (
        "rice_sheen.jsonl",
        None,
        [
            ("measured", field("measured")),
            ("a chalky sheen, cream", value("before")),
            ("the wet film, warm white", value("now")),
        ],
    ),
    "furnace": (
        "furnace.jsonl",
        None,
        [("in the furnace", field("skin")), ("grain / sky", value("mean"))],
    ),
    "flip": (
        "flip.jsonl",
        lambda r: "pair" not in r,
        [
            ("scene", code("recipe")),
            ("size", field("size")),
            ("preview", field("preview")),
            ("Cycles", field("cycles")),
            ("FLIP mean / p95, before", value("before")),
            ("FLIP mean / p95, now", value("after")),
            ("mean sRGB of the eggs (or rice): preview · Cycles before · now", value("eggs")),
        ],
    ),
    "flip_floor": (
        "flip.jsonl",
        lambda r: "pair" in r,
        [
            ("build", field("build")),
            ("pair: test against reference", field("pair")),
            ("frame", value("frame")),
            ("p95", value("p95")),
            ("eggs", value("eggs")),
            ("rice", value("rice")),
            ("bowl", value("bowl")),
            ("table and props", value("table")),
        ],
    ),
    "blender_instancing": (
        "blender_instancing.jsonl",
        None,
        [
            ("file", field("file")),
            ("objects", value("objects")),
            ("meshes", value("meshes")),
            ("mesh data", value("mesh_data")),
            ("import s", value("import_s")),
            ("bytes", value("bytes")),
        ],
    ),
    "preview_budget": (
        "preview_budget.jsonl",
        None,
        [
            ("recipe", lambda r: r.get("recipe", "ikura_don")),
            ("scene of", lambda r: r["date"][:10]),
            ("spp", lambda r: str(r["config"]["spp"])),
            ("seed", lambda r: number(r["config"].get("seed"))),
            ("roulette from bounce", lambda r: str(r["config"]["rr_depth"])),
            ("glint spp", lambda r: str(r["config"]["glint_spp"])),
            ("guide spp", lambda r: str(r["config"]["guide_spp"])),
            ("PSNR (dB)", value("psnr")),
            ("SSIM", value("ssim")),
            ("FLIP", value("flip")),
            ("FLIP over the frame to the most spp, seed 0", value("flip_frame")),
            ("CPU s", value("cpu")),
        ],
    ),
    "preview_sample_cost": (
        "preview_sample_cost.jsonl",
        None,
        [("variant", field("variant")), ("CPU s", value("cpu")), ("eggs' red (linear)", value("eggs_red"))],
    ),
    "rice_denoise": (
        "rice_denoise.jsonl",
        lambda r: "flip_denoised" in r["values"],
        [
            ("rice", field("rice")),
            ("guide passes", lambda r: str(r["config"]["guide_passes"])),
            ("OIDN clean_aux", lambda r: "on" if r["config"]["clean_aux"] else "off"),
            ("FLIP against 64 spp + OIDN: frame / rice", pair("flip_denoised", "flip_denoised_rice")),
            ("FLIP against 64 spp, no denoiser: frame / rice", pair("flip_noisy", "flip_noisy_rice")),
            (
                "rice sRGB: preview · 64 spp + OIDN",
                lambda r: " · ".join((r["values"]["rice"], r["values"]["rice_reference"])),
            ),
            ("3-spp passes, wall s", value("layers_wall")),
        ],
    ),
    "rice_look": (
        "rice_denoise.jsonl",
        lambda r: "quantity" in r,
        [("", field("quantity")), ("before", value("before")), ("now", value("after"))],
    ),
    "preview_guides": (
        "preview_guides.jsonl",
        None,
        [
            ("guide spp", lambda r: str(r["config"]["guide_spp"])),
            ("OIDN", lambda r: r["config"]["oidn"]),
            ("PSNR (dB)", value("psnr")),
            ("SSIM", value("ssim")),
        ],
    ),
    "latency": (
        "latency.jsonl",
        None,
        [
            ("what", field("what")),
            ("wall s", value("wall")),
            ("CPU s", value("cpu")),
            ("load", field("load")),
            ("command", code("command")),
        ],
    ),
    "recording": (
        "recording.jsonl",
        None,
        [
            (".rrd MB", value("rrd_mb")),
            ("chunks (MiB, count)", lambda r: f"{r['values']['chunks_mib']} MiB, {r['values']['chunks']}"),
            ("entities with data", value("entities")),
            ("`/shade/scene` MiB", value("shade_scene_mib")),
            ("read into a chunk store s", value("read_s")),
            ("viewer ingest s", value("viewer_ingest_s")),
            ("shade's outputs logged s", value("shade_log_s")),
        ],
    ),
    "rerun_logging": (
        "rerun_logging.jsonl",
        None,
        [
            ("node", field("node")),
            ("load ms", value("load_ms")),
            ("cold log ms", value("cold_log_ms")),
            ("cached replay ms", value("replay_ms")),
            ("fragment MB", value("fragment_mb")),
        ],
    ),
    "cost_estimate": (
        "cost.jsonl",
        lambda r: "size" in r,
        [
            ("recipe", code("recipe")),
            ("run", lambda r: r["size"] + (f", {r['threads']} thread" if r.get("threads") else "")),
            ("elements", pair("elements_estimate", "elements_measured")),
            ("particles", pair("particles_estimate", "particles_measured")),
            ("sim CPU s", pair("sim_cpu_s_estimate", "sim_cpu_s_measured")),
            ("run CPU s", pair("cpu_s_estimate", "cpu_s_measured")),
            ("peak RSS MiB", pair("peak_rss_mib_estimate", "peak_rss_mib_measured")),
            ("check s", value("check_s")),
            ("load", field("load")),
        ],
    ),
    "check_time": (
        "cost.jsonl",
        lambda r: "wall_s" in r["values"],
        [
            ("what", field("what")),
            ("wall s", value("wall_s")),
            ("CPU s", value("cpu_s")),
            ("load", field("load")),
        ],
    ),
    "interrupt": (
        "interrupt.jsonl",
        None,
        [
            ("what", field("what")),
            ("SIGINT → exit s", value("sigint_s")),
            ("SIGTERM → exit s", value("sigterm_s")),
            ("left running", value("left")),
            ("load", field("load")),
            ("command", code("command")),
        ],
    ),
    "cache_entries": (
        "cache.jsonl",
        None,
        [
            ("what", field("what")),
            ("stored MB", value("stored_mb")),
            ("computed in s", value("compute_s")),
            ("loaded in s", value("load_s")),
            ("share of the cache", value("share")),
            ("load", field("load")),
        ],
    ),
    "sizes": (
        "sizes.jsonl",
        lambda r: r["table"] == "sizes",
        [
            ("element or prop", field("element")),
            ("published", field("published")),
            ("source", field("source")),
            ("the exported file measures", field("measured")),
        ],
    ),
    "rice_cost": (
        "sizes.jsonl",
        lambda r: r["table"] == "rice_cost",
        [
            ("scene", field("element")),
            ("grains", value("grains")),
            ("CPU s (user + sys)", value("cpu")),
            ("wall s", value("wall")),
            ("where it moved (node CPU s)", field("measured")),
        ],
    ),
    "rice_files": (
        "sizes.jsonl",
        lambda r: r["table"] == "rice_files",
        [
            ("exported file", field("element")),
            ("grains", value("grains")),
            ("skin bumps: median / p95", pair("bumps_median", "bumps_p95")),
            ("overlap / length: p95 / max", pair("overlap_p95", "overlap_max")),
        ],
    ),
    "servings": (
        "sizes.jsonl",
        lambda r: r["table"] == "servings",
        [
            ("dish", field("element")),
            ("a real serving", field("published")),
            ("source", field("source")),
            ("it holds", field("holds")),
            ("the scene holds", field("measured")),
        ],
    ),
    "rice_bowl_layer": (
        "rice_bowl.jsonl",
        lambda r: r["table"] == "rice_bowl_layer",
        [
            ("the chawan's top layer", field("element")),
            ("grains", value("grains")),
            ("contacts per grain", value("contacts")),
            ("touching pairs", value("pairs")),
            ("what the picture shows", field("measured")),
        ],
    ),
    "cut_islands": (
        "cut.jsonl",
        None,
        [
            ("`cut.islands`", field("islands")),
            ("grains kept", value("kept")),
            ("pieces", value("pieces")),
            ("", field("note")),
        ],
    ),
}


# tables whose source line names only the data (a README table, kept short: the load is one of its columns)
BRIEF = {"first_hour"}


def render(name: str) -> str:
    """One table in Markdown, with a line saying where, how and when its figures were measured."""
    file, keep, columns = TABLES[name]
    files = (file,) if isinstance(file, str) else file
    rows = [r for f in files for r in records(f) if keep is None or keep(r)]
    lines = ["| " + " | ".join(h for h, _ in columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(cell(r) for _, cell in columns) + " |" for r in rows]

    def distinct(key):
        return list(dict.fromkeys(str(r.get(key, "")) for r in rows if r.get(key)))

    data = ", ".join(f"`benchmarks/measured/{f}`" for f in files)
    if name in BRIEF:  # the load is a column; the commands and dates are in the data
        return "\n".join(lines) + f"\n\nMeasured on {', '.join(distinct('machine'))}; commands and dates: {data}.\n"
    shown = any(h == "command" for h, _ in columns)
    commands = "" if shown else " by " + " · ".join(f"`{c}`" for c in distinct("command"))
    source = (
        f"Measured on {', '.join(distinct('machine'))}{commands}; load {', '.join(distinct('load'))}; "
        f"{', '.join(distinct('date'))}. Data: {data}."
    )
    return "\n".join(lines) + "\n\n" + source + "\n"


def rewrite(text: str) -> str:
    """The text with every marked table rendered from the data; an unknown table name raises KeyError."""
    return MARKER.sub(lambda m: m.group(1) + render(m.group("name")) + m.group(4), text)


def documents() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 if a doc is stale")
    args = parser.parse_args(argv)
    stale = []
    for path in documents():
        text = path.read_text()
        new = rewrite(text)
        if new != text:
            stale.append(path.relative_to(ROOT))
            if not args.check:
                path.write_text(new)
    verb = "stale" if args.check else "rewritten"
    for path in stale:
        print(f"{path}: {verb}")
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
