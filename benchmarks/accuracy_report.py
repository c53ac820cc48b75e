"""docs/accuracy.md: what accuracy costs in time, for every knob the benchmarks measure, in one command.

    python benchmarks/accuracy_report.py            # --quick modes (minutes on 2 loaded cores)
    python benchmarks/accuracy_report.py --full     # the benchmarks' full sweeps (many times longer)

Runs ``bench_elements``, ``bench_placement``, ``bench_xpbd --only accuracy`` and ``bench_shading`` (each in
a child process, results in a temporary folder) and ``nodegraph sweep graphs/sweeps/rice_bowl_solver.yaml``
on a fresh cache; writes docs/accuracy.md (tables, the default of each knob in bold and why it was chosen)
and its plots under docs/images/accuracy/. The header names the machine, its load and the date.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "accuracy.md"
IMAGES = ROOT / "docs" / "images" / "accuracy"
SWEEP_RECIPE = ROOT / "graphs" / "sweeps" / "rice_bowl_solver.yaml"


def machine() -> str:
    model = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        mem = int(Path("/proc/meminfo").read_text().split()[1]) / 2**20
        memory = f", {mem:.0f} GiB RAM"
    except (OSError, ValueError, IndexError):
        memory = ""
    system = f"{platform.system()} {platform.release()}, Python {platform.python_version()}"
    return f"{model}, {os.cpu_count()} cores{memory}; {system}"


def run(args: list[str], results: Path, log: list[str]) -> str:
    env = dict(os.environ, NODEGRAPH_BENCH_RESULTS=str(results), MPLBACKEND="Agg")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    start = time.perf_counter()
    print("$ " + " ".join(args), flush=True)
    done = subprocess.run([sys.executable, *args], cwd=ROOT, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        sys.stderr.write(done.stdout[-3000:] + done.stderr[-3000:])
        raise SystemExit(f"{' '.join(args)} failed (exit {done.returncode})")
    log.append(f"`python {' '.join(args)}`: {seconds:.0f} s")
    return done.stdout


def tables(markdown: str) -> list[tuple[list[str], list[list[str]]]]:
    """Every Markdown table in a text: (header, rows of cells)."""
    found, lines = [], markdown.splitlines()
    i = 0
    while i < len(lines):
        if lines[i].startswith("|") and i + 1 < len(lines) and re.match(r"^\|[-| :]+\|?$", lines[i + 1].strip()):
            header = [c.strip() for c in lines[i].strip().strip("|").split("|")]
            rows = []
            i += 2
            while i < len(lines) and lines[i].startswith("|"):
                rows.append([c.strip() for c in lines[i].strip().strip("|").split("|")])
                i += 1
            found.append((header, rows))
        else:
            i += 1
    return found


def render(header, rows, is_default) -> str:
    """A Markdown table with the default rows in bold; columns empty in every row are dropped."""
    keep = [j for j in range(len(header)) if any(j < len(r) and r[j] for r in rows)]
    out = ["| " + " | ".join(header[j] for j in keep) + " |", "|" + "---|" * len(keep)]
    for row in rows:
        cells = [row[j] if j < len(row) else "" for j in keep]
        if is_default(dict(zip(header, row))):
            cells = [f"**{c}**" if c else c for c in cells]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def copy_image(results: Path, name: str, target: str) -> str:
    IMAGES.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(results / name, IMAGES / target)
    return f"![{target}](images/accuracy/{target})"


def defaults() -> dict[str, object]:
    sys.path.insert(0, str(ROOT))
    from nodegraph.registry import default_registry

    registry = default_registry()
    get = lambda node, param: registry.get(node).params[param].default
    return {
        "resolution": get("voxelise", "resolution"),
        "method": get("distance_field", "method"),
        "candidate_spacing": get("poisson_place", "candidate_spacing"),
        "candidates": get("poisson_place", "candidates"),
        "tolerance": get("overlap_refine", "tolerance"),
        "sphere_tolerance": get("overlap_refine", "sphere_tolerance"),
        "max_spheres": get("overlap_refine", "max_spheres"),
        "cost": get("overlap_refine", "cost"),
        "substeps": get("xpbd", "substeps"),
        "iterations": get("xpbd", "iterations"),
        "table_size": get("shade", "table_size"),
    }


def number(text: str) -> float:
    try:
        return float(text.replace("%", "").replace(",", "").replace("*", "").strip())
    except ValueError:
        return float("nan")


def pick(rows, header, **match) -> dict | None:
    """The first row (as a dict by header) whose cells equal ``match`` (numbers compared as numbers)."""
    for row in rows:
        cells = dict(zip(header, row))
        if all(number(cells.get(k, "")) == v if isinstance(v, (int, float)) else cells.get(k) == v
               for k, v in match.items()):  # fmt: skip
            return cells
    return None


def elements_section(out: str, d, results) -> list[str]:
    header, rows = tables(out)[0]
    default = lambda r: number(r["res"]) == d["resolution"] and r["method"] == d["method"]
    res = d["resolution"]
    at = {m: pick(rows, header, res=res, method=m) for m in ("exact", "euclidean", "manhattan")}
    lower = max((number(r[0]) for r in rows if number(r[0]) < res), default=None)
    higher = min((number(r[0]) for r in rows if number(r[0]) > res), default=None)
    why = [f"**Default: resolution {res}, route `{d['method']}`.**"]
    if all(at.values()):
        why.append(
            f"At {res} the exact route's offset surface (what `expand` grows, G eq. 5–6) is off by "
            f"{at['exact']['offset mean (voxels)']} voxel, against {at['euclidean']['offset mean (voxels)']} "
            f"(euclidean) and {at['manhattan']['offset mean (voxels)']} (manhattan), and its mean surface error "
            f"is {at['exact']['mean (L)']} of the grain length against {at['euclidean']['mean (L)']}: the grid "
            "metrics' error is a fixed fraction of a voxel, the exact route's is not, which is why `exact` is "
            "the default although it is not the fastest route."
        )
    for other, word in ((lower, "Halving"), (higher, "Doubling")):
        row = other and pick(rows, header, res=other, method=d["method"])
        if row and at["exact"]:
            why.append(
                f"{word} the resolution ({other:g}) gives a mean error of {row['mean (L)']} (vs "
                f"{at['exact']['mean (L)']}) in {row['ms/grain']} ms per grain (vs {at['exact']['ms/grain']} ms)."
            )
    if at["exact"]:
        per = number(at["exact"]["ms/grain"])
        why.append(
            f"At {res} a library of 16 variants costs about {16 * per / 1000:.1f} s here, while the error is a few "
            "hundredths of a voxel: the resolution where time, not accuracy, becomes what a recipe notices."
        )
    return [
        "## Grain modelling: voxel resolution × distance route (`voxelise.resolution`, `distance_field.method`)",
        "",
        "`benchmarks/bench_elements.py`: one japonica grain through sphere_scatter → remesh; errors against the exact "
        "surface of base mesh ∪ spheres (L = grain length).",
        "",
        render(header, rows, default),
        "",
        copy_image(results, "bench_elements.png", "elements.png"),
        "",
        " ".join(why),
        "",
    ]


def _ratio(a, b) -> str:
    a, b = number(a), number(b)
    return f"{a / b:.1f}×" if b else "—"


def why_spacing(sel, header, d) -> str:
    base = pick(sel, header, setting=d["candidate_spacing"])
    parts = [f"**Default {d['candidate_spacing']:g}** (S: candidate edges ≤ r)."]
    for row in (dict(zip(header, r)) for r in sel):
        if base and row is not base and row["setting"] != base["setting"]:
            change = number(row["placed"]) / number(base["placed"]) - 1
            parts.append(
                f"Spacing {row['setting']} × r: {row['placed']} placed ({change:+.1%}) from {row['candidates']} "
                f"candidates in {row['place_s']} s ({_ratio(row['place_s'], base['place_s'])} the default's time)."
            )
    parts.append(
        "Coarser candidates leave the placement short of maximal; finer ones multiply the candidates (memory, "
        "and the dart throwing's work) for the few percent more elements the table shows, so S's spacing is kept."
    )
    return " ".join(parts)


def why_tolerance(sel, header, d) -> str:
    rows = [dict(zip(header, r)) for r in sel]
    listed = "; ".join(
        f"{r['setting']}: mean overlap {r['overlap_mean_L']} L, culled {r['culled']}, {r['refine_s']} s" for r in rows
    )
    import math

    steps = "; ".join(f"{r['setting']}: {math.log(number(r['setting'])) / math.log(0.618):.0f}" for r in rows)
    return (
        f"**Default {d['tolerance']:g}** of the search range. Measured — {listed}. The residual overlap and the "
        "share culled barely move across these tolerances; the golden-section evaluations per element grow with "
        f"log(1/tolerance) (the bracket shrinks by 0.618 per step: {steps}), although the timings here differ "
        "by less than this loaded machine's noise. 0.01 is the loosest bracket whose overlap equals the tightest's."
    )


def why_spheres(sel, header, d) -> str:
    rows = [dict(zip(header, r)) for r in sel]
    listed = "; ".join(
        f"{r['setting']}: {r['spheres']} spheres, fit gap {r['fit_gap_max_L']} L, "
        f"implicit functions {r['implicit_s']} s, mean overlap {r['overlap_mean_L']} L"
        for r in rows
    )
    return (
        f"**Default tolerance {d['sphere_tolerance']:g} (at most {d['max_spheres']} spheres).** Measured — {listed}. "
        "The sphere count (and the refine's cost, linear in it) grows fast as the tolerance shrinks, while the "
        "overlap after refine does not follow the fit gap down: the default sits where the fit gap is already "
        "a small share of the element and the count still modest."
    )


def why_cost(sel, header, d) -> str:
    rows = {r[1]: dict(zip(header, r)) for r in sel}
    s, g = rows.get("sakurai"), rows.get("gan")
    text = f"**Default `{d['cost']}`** (S eq. 2)."
    if s and g:
        text += (
            f" Here it leaves mean overlap {s['overlap_mean_L']} L (G eq. 1: {g['overlap_mean_L']}), culls "
            f"{s['culled']} (G: {g['culled']}) and takes {s['refine_s']} s ({g['refine_s']} s for G eq. 1)."
        )
    return text


PLACEMENT_GROUPS = (
    (
        "candidate spacing (×r)",
        "Candidate density (`poisson_place.candidate_spacing`)",
        "candidate_spacing",
        why_spacing,
    ),
    ("golden tolerance", "Golden-section tolerance (`overlap_refine.tolerance`)", "tolerance", why_tolerance),
    (
        "medial spheres (tol)",
        "Medial-sphere count (`overlap_refine.sphere_tolerance`, `max_spheres`)",
        "sphere_tolerance",
        why_spheres,
    ),
    ("cost", "Cost function (`overlap_refine.cost`)", "cost", why_cost),
)


def placement_section(out: str, d, results) -> list[str]:
    header, rows = tables(out)[0]
    lines = [
        "## Placement knobs (`benchmarks/bench_placement.py`)",
        "",
        "The S onigiri setup (surface mode); overlap in element lengths L, share culled at D = 0.1 mm.",
        "",
    ]
    for group, title, key, why in PLACEMENT_GROUPS:
        sel = [r for r in rows if r[0] == group]
        if not sel:
            continue
        value = d[key]
        is_default = lambda r, v=value: r["setting"] == v if isinstance(v, str) else number(r["setting"]) == v
        lines += [f"### {title}", "", render(header, sel, is_default), "", why(sel, header, d), ""]
    lines += [copy_image(results, "bench_placement.png", "placement.png"), ""]
    return lines


def xpbd_section(out: str, d, results, quick: bool) -> list[str]:
    text = out.split("Energy drift:", 1)
    body = "Energy drift:" + text[1] if len(text) == 2 else out
    default = f"| {d['substeps']} | {d['iterations']} |"
    body = "\n".join(
        ("| " + " | ".join(f"**{c.strip()}**" for c in line.strip().strip("|").split("|")) + " |")
        if line.startswith(default)
        else line
        for line in body.splitlines()
    )
    found = tables(out)
    why = [f"**Default {d['substeps']} substeps × {d['iterations']} iterations.**"]
    if len(found) >= 2:
        header, rows = found[-1]  # the stack: an analytic rest
        error = next(h for h in header if h.startswith("mean position error vs analytic"))
        front = next(h for h in header if h.startswith("Pareto"))
        base = pick(rows, header, substeps=d["substeps"], iterations=d["iterations"])
        if base:
            why.append(
                f"On the stack (exact rest known) it settles within {base[error]} mm of the rest in "
                f"{base['wall (s)']} s, {'on' if '★' in base[front] else 'off'} the Pareto front, with max "
                f"penetration {base['max penetration / r']} r."
            )
            cheaper = [dict(zip(header, r)) for r in rows if number(r[2]) < number(base["wall (s)"])]
            if cheaper:
                best = min(cheaper, key=lambda r: number(r[error]))
                why.append(
                    f"The most accurate cheaper setting measured, {best['substeps']} × {best['iterations']}, is "
                    f"{_ratio(best[error], base[error])} as far from the rest."
                )
        a, b = pick(rows, header, substeps=16, iterations=1), pick(rows, header, substeps=4, iterations=4)
        if a and b:
            why.append(
                f"Substeps buy more than iterations (small steps, Macklin et al. 2019): 16 × 1 ends {a[error]} mm "
                f"from the rest, 4 × 4 {b[error]} mm, for the same number of constraint passes."
            )
    return [
        "## Simulation: substeps × iterations (`xpbd.substeps`, `xpbd.iterations`)",
        "",
        "`benchmarks/bench_xpbd.py --only accuracy`: a bowl of grains and a stack of cubes with a known rest; "
        "★ on the Pareto front of the position error, ☆ of the second error.",
        "",
        body.strip(),
        "",
        copy_image(results, f"bench_xpbd_accuracy{'_quick' if quick else ''}.png", "xpbd.png"),
        "",
        " ".join(why),
        "",
    ]


def sweep_section(sweep_md: str, results) -> list[str]:
    body = sweep_md.split("\n", 1)[1]  # drop the sweep's own heading
    body = re.sub(r"!\[[^\]]*\]\([^)]*\)", "", body).strip()
    header, rows = tables(sweep_md)[0]
    metric = "contacts.stats.penetration_max_r"
    cells = [dict(zip(header, [c.replace("*", "") for c in r])) for r in rows]
    base = next((c for c in cells if c["recipe setting"] == "yes"), None)
    why = ""
    if base:
        seconds = [number(c["seconds"]) for c in cells]
        beaten = [
            c
            for c in cells
            if number(c["seconds"]) <= number(base["seconds"]) and number(c[metric]) < number(base[metric])
        ]
        work = sorted(cells, key=lambda c: number(c["rice_sim.substeps"]) * number(c["rice_sim.iterations"]))
        quarter = max(1, len(work) // 4)
        low = sorted(number(c["seconds"]) for c in work[:quarter])[quarter // 2]
        high = sorted(number(c["seconds"]) for c in work[-quarter:])[quarter // 2]
        growth = (
            "the time hardly grows with substeps × iterations (not broken down here; a fixed per-run part and "
            "grains that go to sleep are the likely reasons)"
            if high < 1.5 * low
            else f"the dearest quarter of the settings takes {high / low:.1f}× the time of the cheapest quarter "
            "(medians)"
        )
        why = (
            f"Here every point costs {min(seconds):.1f}–{max(seconds):.1f} s; over these few frames {growth}, "
            "and the recipe's 10 × 2 "
            f"(bold: max overlap {base[metric]} r in {base['seconds']} s) is "
            + (
                "on the front."
                if not beaten
                else "not on the front: "
                + ", ".join(f"{c['rice_sim.substeps']} × {c['rice_sim.iterations']}" for c in beaten)
                + " reached less overlap in no more time (on this shared machine single timings are noisy). "
                "The default was chosen on the benchmark scenes above; this sweep is the evidence for the "
                "simulation's owner to revisit it on the bowl."
            )
        )
    return [
        "## The rice bowl itself: `nodegraph sweep graphs/sweeps/rice_bowl_solver.yaml`",
        "",
        "The same knobs on the real recipe (its grains, placement and collider), through the sweep command: "
        "residual overlap between grains after the frames (`particle_contacts`), in particle radii.",
        "",
        body,
        "",
        copy_image(results, "substeps_iterations.png", "rice_bowl_solver.png"),
        "",
        why,
        "",
    ]


def shading_section(out: str, d, results) -> list[str]:
    header, rows = tables(out)[0]
    size = tuple(d["table_size"])
    label = f"table {size[0]}×{size[1]}"
    base = pick(rows, header, method=label)
    exact = rows[0]
    quadrature = [dict(zip(header, r)) for r in rows if r[0].startswith("quadrature")]
    why = f"**Default {label}.**"
    if base:
        why += (
            f" One interpolated lookup per vertex: {base['time per frame (ms)']} ms per frame against "
            f"{exact[1]} ms for the closed form (complex erf); its max error {base['max error']} is below one 8-bit "
            "colour step (1/255 ≈ 3.9e-03), which the smaller tables' are not. Larger tables cost the same per "
            "frame (one lookup) and 4× the memory per doubling, for errors already below what 8-bit colour shows."
        )
        if quadrature:
            q = quadrature[-1]
            why += f" Quadrature ({q['method']}) still errs by up to {q['max error']} in {q['time per frame (ms)']} ms."
    return [
        "## CDRF approximation (`shade.table_size`)",
        "",
        "`benchmarks/bench_shading.py`: the fitted lookup table and n-point quadrature against the closed form "
        "(SPEC §4 eq. 7), per frame of per-vertex (θ, σ) samples like a rice scene's.",
        "",
        render(header, rows, lambda r: r["method"] == label),
        "",
        copy_image(results, "bench_shading.png", "shading.png"),
        "",
        why,
        "",
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true", help="the benchmarks' full modes (slow), not --quick")
    args = parser.parse_args()
    quick = not args.full
    flag = ["--quick"] if quick else []
    started = datetime.datetime.now().astimezone()
    load_start = os.getloadavg()
    t0 = time.perf_counter()
    log: list[str] = []
    d = defaults()
    with tempfile.TemporaryDirectory() as tmp:
        results = Path(tmp)
        elements = run(["benchmarks/bench_elements.py", *flag], results, log)
        placement = run(["benchmarks/bench_placement.py", *flag], results, log)
        xpbd = run(["benchmarks/bench_xpbd.py", "--only", "accuracy", *flag], results, log)
        shading = run(["benchmarks/bench_shading.py", *flag], results, log)
        run(
            ["-m", "nodegraph.cli", "sweep", str(SWEEP_RECIPE.relative_to(ROOT)), "-q"]
            + ["--out-dir", str(results), "--cache-dir", str(results / "cache")],
            results,
            log,
        )
        sweep_md = (results / "substeps_iterations.md").read_text()
        load_end = os.getloadavg()
        mode = (
            "**quick mode** (`--quick`: fewer resolutions, smaller scenes, fewer repeats) because the full "
            "sweeps (resolutions up to 256, the full-size S setup, a 50,000-element refine, 150-grain bowls) take "
            "many times longer on this loaded 2-core machine; `--full` runs them"
            if quick
            else "full mode"
        )
        lines = [
            "# Accuracy against time",
            "",
            f"Generated by `python benchmarks/accuracy_report.py{'' if quick else ' --full'}` on "
            f"{started:%Y-%m-%d %H:%M %Z}. Machine: {machine()}. Load average (1 min) {load_start[0]:.2f} at the "
            f"start, {load_end[0]:.2f} at the end (the machine is shared: timings carry that noise). {mode}. "
            f"Took {time.perf_counter() - t0:.0f} s: " + "; ".join(log) + ".",
            "",
            "Each section: the knob, the measured table (the default in **bold**), the plot, and why the default "
            "is what it is. Errors are lower-is-better; the Pareto front is the set of settings no other beats on "
            "both time and error.",
            "",
            *elements_section(elements, d, results),
            *placement_section(placement, d, results),
            *xpbd_section(xpbd, d, results, quick),
            *sweep_section(sweep_md, results),
            *shading_section(shading, d, results),
            "## Not measured yet",
            "",
            "Knobs that trade accuracy for time but have no benchmark sweep yet, so no table here: "
            "`expand` expansion, `remesh.target_faces`, `xpbd.particles_per_element` against a mesh-level overlap "
            "measure, and `preview.samples`. Each becomes a section once a benchmark or a `graphs/sweeps/` recipe "
            "measures it.",
            "",
        ]
    DOC.write_text("\n".join(lines))
    print(f"wrote {DOC} and {IMAGES}/")


if __name__ == "__main__":
    main()
