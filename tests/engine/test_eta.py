"""A run's ETA comes from the time each node took when it last ran, not from the count of instances done
(issue 47: "93/97 … eta 0:00:02" during an 80 s preview)."""

import io
import time

import pytest
from rich.console import Console

from nodegraph.executor import run_recipe
from nodegraph.recipe import parse_recipe
from nodegraph.report import Reporter

RECIPE = """\
name: etarun
seed: 1
outputs: [slow]
nodes:
  pts: {type: toy_points, params: {count: COUNT}}
  slow: {type: toy_slow, inputs: {spheres: pts.spheres}, params: {seconds: 0.4}}
"""


class PlanSeen(Reporter):
    def __init__(self):
        super().__init__(quiet=True)
        self.plans = []

    def task(self, description, total, plan=None):
        self.plans.append(plan)
        return super().task(description, total)


def test_the_plan_expects_each_node_to_take_as_long_as_it_last_did(registry, cache):
    run_recipe(parse_recipe(RECIPE.replace("COUNT", "5"), registry), cache=cache, reporter=PlanSeen())
    seen = PlanSeen()
    run_recipe(parse_recipe(RECIPE.replace("COUNT", "6"), registry), cache=cache, reporter=seen)
    pts, slow = seen.plans[0]  # both run again (a new count): their last times, the slow one ≈ 0.4 s
    assert pts is not None and slow is not None and slow >= 0.4 and slow > pts


def test_a_node_that_never_ran_is_expected_to_take_what_the_estimate_says_or_nothing_is_claimed(registry, cache):
    """A first run kept no times: its bar counted nodes ("89/97 … eta 0:00:01" for minutes); now the estimate's
    seconds, and where there is none, no ETA at all."""
    from nodegraph.cost import Cost, Estimate

    seen = PlanSeen()
    estimate = Estimate(costs={"pts": Cost(), "slow": Cost(seconds=30.0)}, outputs=("slow",))
    run_recipe(parse_recipe(RECIPE.replace("COUNT", "7"), registry), cache=cache, reporter=seen, estimate=estimate)
    assert seen.plans[0] == [pytest.approx(estimate.other_seconds), 30.0]
    seen = PlanSeen()
    run_recipe(parse_recipe(RECIPE.replace("COUNT", "8"), registry), cache=None, reporter=seen)
    assert seen.plans[0] == [None, None]
    out = io.StringIO()
    reporter = Reporter(console=Console(file=out, force_terminal=True, width=120))
    with reporter.task("etarun", 2, plan=[None, None]) as tick:
        tick()
        reporter._progress.refresh()
    assert "-:--:--" in out.getvalue() and "≥" not in out.getvalue()  # not "≥ 0:00:00"


def test_remaining_seconds_counts_what_is_ahead_and_what_is_left_of_the_running_step():
    from nodegraph.report import remaining_seconds

    plan = [0.05] * 93 + [80.0, 0.1, 0.1, 0.1]
    now = time.monotonic()
    assert remaining_seconds(plan, 94, now - 10.0, now) == (pytest.approx(70.3), True)  # 10 s into the 80 s step
    assert remaining_seconds(plan, 94, now - 100.0, now)[0] == pytest.approx(0.3)  # overrun: what follows it
    assert remaining_seconds([1.0, None, 2.0], 1, now, now) == (3.0, False)  # a lower bound


def test_the_bar_shows_the_planned_eta():
    out = io.StringIO()
    reporter = Reporter(console=Console(file=out, force_terminal=True, width=120))
    with reporter.task("etarun", 3, plan=[0.1, 600.0, 0.1]) as tick:
        tick()
        tick()  # the 10-minute step begins
        reporter._progress.refresh()
    assert "0:10:00" in out.getvalue()
