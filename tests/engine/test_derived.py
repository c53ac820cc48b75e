"""``codec.derived``: what a node derives from a frozen input alone is kept with that input while it lives, so a
watched re-run on the same input does not rebuild it; an input that could still change is not kept."""

import gc
from dataclasses import dataclass

import numpy as np

from nodegraph.codec import derived, freeze, is_frozen


@dataclass(frozen=True, eq=False)
class Points:
    xyz: np.ndarray


def test_a_frozen_value_derives_once_and_frees_with_the_value():
    calls = []

    def total(value):
        calls.append(1)
        return np.array([value.xyz.sum()])

    value = freeze(Points(np.arange(6.0)))
    first = derived(value, "total", total)
    assert derived(value, "total", total) is first and len(calls) == 1
    assert not first.flags.writeable  # what is kept is frozen too: no caller can change it for the next
    derived(value, "other", total)
    assert len(calls) == 2  # another name, another derivation
    other = freeze(Points(np.arange(6.0)))  # equal, but another value: its own
    derived(other, "total", total)
    assert len(calls) == 3
    from nodegraph import codec

    del value, first
    gc.collect()
    assert len(codec._DERIVED) == 1  # only `other` is still alive


def test_an_unfrozen_value_is_derived_every_time():
    calls = []
    value = Points(np.arange(3.0))
    assert not is_frozen(value)
    for _ in range(2):
        derived(value, "total", lambda v: calls.append(1) or v.xyz.sum())
    assert len(calls) == 2
    assert derived((1, 2), "sum", sum) == 3  # nothing to keep it with: computed
