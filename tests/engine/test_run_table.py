"""The closing table of a run fits an 80-column terminal: one line per node, no cell wrapped; in a pipe it is
printed whole, nothing cut, and short: only the steps that took a second or more (issue 47)."""

import io

from rich.console import Console

from nodegraph.report import NodeRecord, Reporter

# the rice bowl's nodes and types: the longest names a run of the project's recipes shows
NODES = [
    ("grain_spheres", "sphere_scatter", 16),
    ("grain_field", "distance_field", 16),
    ("rice", "element_library", 1),
    ("implicit", "medial_spheres", 1),
    ("rice_place", "poisson_place", 1),
    ("refine", "overlap_refine", 1),
    ("contact", "deform_contacts", 1),
    ("preview", "preview", 1),
]


def table_lines(width: int, terminal: bool = True) -> list[str]:
    out = io.StringIO()
    reporter = Reporter(console=Console(file=out, width=width, force_terminal=terminal, color_system=None))
    for i, (node, kind, count) in enumerate(NODES):
        for v in range(count):
            label = node if count == 1 else f"{node}[{v}]"
            status = "ran" if i % 2 else "cached"
            reporter.record(NodeRecord(label, kind, status, 97.3 * i, 1.7 * 2**30, 0.0123, cpu_seconds=123.4 * i))
    reporter.print_summary()
    return out.getvalue().splitlines()


def test_the_run_table_fits_80_columns_one_line_per_node():
    lines = table_lines(80)
    rows = [line for line in lines if line.startswith("│")]
    assert len(rows) == len(NODES), "\n".join(lines)  # no cell wrapped onto a second line
    assert max(len(line) for line in lines) <= 80
    assert rows[0].split("│")[1].strip() == "grain_spheres" and "cached ×16" in rows[0]
    wide = table_lines(160)
    assert "deform_contacts" in "\n".join(wide)  # the type column where there is room


def test_in_a_pipe_the_table_is_whole_and_no_memory_is_negative():
    """Issue 47: a table printed to a pipe was cut ("wall ti…"), and a node's peak memory read "-0.2 MiB"."""
    lines = table_lines(80, terminal=False)
    text = "\n".join(lines)
    assert "…" not in text and "wall time" in text and "deform_contacts" in text  # every column, whole
    # short: the steps under a second (grain_spheres ×16, 0 s) counted in a line, not listed
    assert len([line for line in lines if line.startswith("│")]) == len(NODES) - 1
    said = " ".join(text.split())  # the caption wraps to the table's width
    assert "and 1 more step under 1 s each: 1 cached (16 with their variants; 0.0 ms in all): grain_spheres" in said
    out = io.StringIO()
    reporter = Reporter(console=Console(file=out, width=80))
    for node, peak in (("frees", -0.2 * 2**20), ("tiny", 300 * 2**10), ("big", 5 * 2**20)):
        reporter.record(NodeRecord(node, "toy", "ran", 1.0, peak, cpu_seconds=1.0))
    reporter.print_summary()
    rows = [line.split("│") for line in out.getvalue().splitlines() if line.startswith("│")]
    cells = {row[1].strip(): row[-2].strip() for row in rows}
    assert cells == {"frees": "< 1 MiB", "tiny": "< 1 MiB", "big": "5.0 MiB"}


def test_durations_read_back():
    from nodegraph.report import format_duration, parse_duration

    for seconds in (0.0002, 0.035, 1.23, 85.1, 987.0, 12000.0):
        assert len(format_duration(seconds)) <= 7
        assert abs(parse_duration(format_duration(seconds)) - seconds) <= 0.01 * seconds + 60 * (seconds > 3600)


def test_a_run_of_quick_steps_prints_no_empty_table():
    """Issue 47: in a pipe, a run whose steps all took under a second printed the table's header box with no row
    in it; now the line that counts them, alone. A run that reached no step prints no table at all."""
    out = io.StringIO()
    reporter = Reporter(console=Console(file=out, width=80))
    for node in ("pts", "merge"):
        reporter.record(NodeRecord(node, "toy", "cached", 0.01))
    reporter.print_summary()
    assert out.getvalue() == "all 2 steps under 1 s each: 2 cached (20 ms in all): pts, merge\n", out.getvalue()
    for terminal in (False, True):
        out = io.StringIO()
        Reporter(console=Console(file=out, width=80, force_terminal=terminal)).print_summary()
        assert out.getvalue() == ""


def test_the_steps_not_listed_are_counted_as_steps():
    """Issue 47: the line read "28 more steps … 116 cached, 2 ran": steps, then their variants, in one breath.
    Each count is of steps now (a step with a variant that ran counts as ran); the variants apart, in brackets."""
    out = io.StringIO()
    reporter = Reporter(console=Console(file=out, width=80))
    reporter.record(NodeRecord("slow", "toy", "ran", 2.0))
    for k in range(16):
        reporter.record(NodeRecord(f"family[{k}]", "toy", "cached", 0.01))
    reporter.record(NodeRecord("pair[0]", "toy", "cached", 0.01))
    reporter.record(NodeRecord("pair[1]", "toy", "ran", 0.01))
    reporter.print_summary()
    said = " ".join(out.getvalue().split())
    assert "and 2 more steps under 1 s each: 1 cached, 1 ran (18 with their variants; 180 ms in all)" in said


def test_the_progress_bar_says_what_it_counts(tmp_path, monkeypatch):
    """Issue 47: the bar read "89/97" for a recipe of fewer steps, its variants counted apart, said nowhere."""
    from pathlib import Path

    from nodegraph.cli import main

    bars = []
    task = Reporter.task

    def recorded(self, description, total, plan=None):
        bars.append((description, total))
        return task(self, description, total, plan)

    monkeypatch.setattr(Reporter, "task", recorded)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "two.yaml").write_text(
        "outputs: [merge.spheres]\nnodes:\n  pts: {type: toy_points, variants: 3}\n"
        "  merge: {type: toy_merge, inputs: {parts: pts.spheres}}\n"
    )
    toy = str(Path(__file__).with_name("toy_nodes.py"))
    assert main(["run", "two.yaml", "-q", "--no-rrd", "--cache-dir", str(tmp_path / "c"), "--plugin", toy]) == 0
    assert bars == [("two: 2 steps, 4 with their variants", 4)]
