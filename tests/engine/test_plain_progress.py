"""Where no progress bar is drawn (a pipe, CI, ``| tee``), a run says each step that took a while as it ends and
each long step while it runs, in plain lines (issue 47: such a run was silent for 27–44 s, then ≈ 200 lines long)."""

import re

from nodegraph import report

from .test_cli_and_rerun import cli

SLOW = """\
name: plainrun
outputs: [slow]
nodes:
  pts: {type: toy_points, params: {count: 6}}
  slow: {type: toy_slow, inputs: {spheres: pts.spheres}, params: {seconds: 0.6}}
"""


def test_a_run_in_a_pipe_prints_a_line_per_long_step_and_a_heartbeat(tmp_path, monkeypatch, capsys):
    """Only the steps that took a while are said and listed (a cold run of the main job printed ≈ 200 lines)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(report, "HEARTBEAT_S", 0.2)
    monkeypatch.setattr(report, "PLAIN_SHOWN_S", 0.3)
    (tmp_path / "plain.yaml").write_text(SLOW)
    assert cli("run", "plain.yaml", "--cache-dir", str(tmp_path / "c"), "--no-rrd") == 0
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert not re.search(r"^pts: done", err, re.M) and not re.search(r"│ pts ", err), err  # milliseconds: a line
    assert "and 1 more step under 0.3 s each: 1 ran" in err and re.search(r"│ slow ", err), err
    assert re.search(r"^slow: running, 0 s so far$", err, re.M), err  # said while it ran
    assert re.search(r"^slow: done in 6\d\d ms$", err, re.M), err
    assert lines.index("slow: running, 0 s so far") < next(i for i, x in enumerate(lines) if x.startswith("slow: done"))
    assert "\r" not in err and "\x1b" not in err  # no bar, no escape codes
    assert cli("run", "plain.yaml", "--cache-dir", str(tmp_path / "c"), "--no-rrd", "-q") == 0
    assert capsys.readouterr().err == ""  # -q: nothing but errors
