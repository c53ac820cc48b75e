"""Toy node types that declare their cost (``nodegraph.cost``): a maker of ``count`` items, a pass-through that
keeps a share, and a stepper whose CPU seconds are items × steps, its lever ``steps``."""

from nodegraph import In, Out, Param, node
from nodegraph.cost import Cost, Lever, estimated_by, passes
from nodegraph.values import Table


def _make_cost(q):
    return Cost(elements=q.params["count"], made=q.params["count"], memory=q.params["count"] * 1000)


def _step_cost(q):
    items = q.elements("table")
    seconds = items * q.params["steps"] * 1e-3
    lever = Lever("steps", lambda budget: f"steps ≤ {int(budget / items / 1e-3)}")
    return Cost(elements=items, particles=items, seconds=seconds, memory=items * 10, time_lever=lever)


@estimated_by(_make_cost)
@node(
    "cost_make",
    outputs={"table": Out(Table, "count items")},
    params={"count": Param(int, 10, "items", range=(1, 10**9))},
)
def cost_make(ctx, *, count):
    """Make count items."""
    return Table({"x": list(range(count))})


@estimated_by(passes("table", 0.5))
@node(
    "cost_half",
    inputs={"table": In(Table, "items")},
    outputs={"table": Out(Table, "every other item")},
)
def cost_half(ctx, table):
    """Keep every other item."""
    return Table({"x": table.columns["x"][::2]})


@estimated_by(_step_cost)
@node(
    "cost_step",
    inputs={"table": In(Table, "items")},
    outputs={"table": Out(Table, "the items, stepped")},
    params={"steps": Param(int, 1, "steps", range=(1, 10**9))},
)
def cost_step(ctx, table, *, steps):
    """Step the items."""
    return table


@estimated_by(passes("table"))
@node(
    "cost_unstored",
    store=False,
    inputs={"table": In(Table, "items")},
    outputs={"table": Out(Table, "the items again")},
)
def cost_unstored(ctx, table):
    """Hand the items on, never stored (made again from the cache in a moment, as the shade node)."""
    return table
