"""friction.contact_groups and friction.carried against their NumPy definitions, on random neighbour lists."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.simulation.buffers import ListRows
from nodes.simulation.friction import ROLLING, carried, contact_groups


class Lists:
    """The part of ``buffers.NeighbourLists`` that ``contact_groups`` reads."""

    def __init__(self, rows: ListRows, half: bool):
        self.nbr_start, self.nbr, self.order, self.half = rows.nbr_start, rows.nbr, rows.order, half

    def rows(self):
        return self.nbr_start, self.nbr, self.half, self.order


def random_lists(rng, n: int, half: bool) -> ListRows:
    """Rows in a shuffled particle order, each with up to 12 distinct neighbours (only higher ids when ``half``)."""
    order = rng.permutation(n)
    rows = []
    for i in order:
        others = np.arange(i + 1, n) if half else np.delete(np.arange(n), i)
        rows.append(rng.choice(others, size=min(len(others), rng.integers(0, 13)), replace=False))
    nbr_start = np.concatenate([[0], np.cumsum([len(r) for r in rows])]).astype(np.int64)
    return ListRows(nbr_start, np.concatenate(rows).astype(np.int64), order.astype(np.int64))


def numpy_groups(rows: ListRows, half: bool, elem, w):
    """The definition: contacts numbered by np.unique of the (lower, higher) element keys of the kept entries."""
    i = np.repeat(rows.order, np.diff(rows.nbr_start))
    j = rows.nbr
    kept = np.ones(len(j), bool) if half else i < j
    sizes = np.bincount(elem)
    lo, hi = np.minimum(elem[i], elem[j]), np.maximum(elem[i], elem[j])
    group = np.full(len(j), -1, np.int64)
    ids, inverse = np.unique((lo * (int(elem.max()) + 1) + hi)[kept], return_inverse=True)
    group[kept] = inverse
    rolls = (sizes[elem[i]] <= ROLLING) | (sizes[elem[j]] <= ROLLING)
    return group, len(ids), np.where(elem[i] <= elem[j], 1.0, -1.0), w[i] + w[j], rolls


@pytest.mark.parametrize("half", [False, True])
def test_contact_groups_match_their_numpy_definition(half):
    rng = np.random.default_rng(7)
    n = 300
    elem = np.sort(rng.integers(0, 60, n))  # elements of 1 to ≈ 10 particles, some of one (they roll)
    w = rng.uniform(0.5, 2.0, n)
    rows = random_lists(rng, n, half)
    got = contact_groups(Lists(rows, half), elem, w)
    want = numpy_groups(rows, half, elem, w)
    assert got.count == want[1]
    for a, b in zip((got.group, got.sign, got.wsum, got.rolls), (want[0], *want[2:])):
        np.testing.assert_array_equal(a, b)


def test_carried_takes_rows_through_sources():
    rng = np.random.default_rng(3)
    source = rng.integers(-1, 40, 100)
    for old, fresh in ((rng.normal(size=(40, 3)), np.nan), (rng.integers(0, 4, 40).astype(np.int8), 0)):
        want = np.full((100, *old.shape[1:]), fresh, old.dtype)
        want[source >= 0] = old[source[source >= 0]]
        got = carried(old, source, fresh)
        assert got.dtype == old.dtype
        np.testing.assert_array_equal(got, want)
    assert carried(np.empty((0, 4)), np.full(5, -1), 0.0).shape == (5, 4)
