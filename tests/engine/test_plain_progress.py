"""Where no progress bar is drawn (a pipe, CI, ``| tee``), a run says each step as it ends and each long step
while it runs, in plain lines (issue 47: such a run was silent for 27–44 s)."""

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


def test_a_run_in_a_pipe_prints_a_line_per_step_and_a_heartbeat(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(report, "HEARTBEAT_S", 0.2)
    (tmp_path / "plain.yaml").write_text(SLOW)
    assert cli("run", "plain.yaml", "--cache-dir", str(tmp_path / "c"), "--no-rrd") == 0
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert re.search(r"^pts: done in [\d.]+ ms$", err, re.M), err
    assert re.search(r"^slow: running, 0 s so far$", err, re.M), err  # said while it ran
    assert re.search(r"^slow: done in 6\d\d ms$", err, re.M), err
    assert lines.index("slow: running, 0 s so far") < next(i for i, x in enumerate(lines) if x.startswith("slow: done"))
    assert "\r" not in err and "\x1b" not in err  # no bar, no escape codes
    assert cli("run", "plain.yaml", "--cache-dir", str(tmp_path / "c"), "--no-rrd", "-q") == 0
    assert capsys.readouterr().err == ""  # -q: nothing but errors
