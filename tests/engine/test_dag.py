"""The recipe graph's own operations give what networkx gives on the same graphs (random ones, with and
without cycles)."""

import random

import networkx as nx

from nodegraph.dag import Dag


def _random_graphs(count: int, acyclic: bool):
    rng = random.Random(7)
    for _ in range(count):
        ids = [f"n{k}" for k in rng.sample(range(100), rng.randint(1, 12))]
        edges = []
        for _ in range(rng.randint(0, 20)):
            a, b = rng.sample(range(len(ids)), 2) if len(ids) > 1 else (0, 0)
            if a == b:
                continue
            if acyclic and a > b:
                a, b = b, a
            edges.append((ids[a], ids[b]))
        ours, theirs = Dag(ids), nx.DiGraph()
        theirs.add_nodes_from(ids)
        for u, v in edges:
            ours.add_edge(u, v)
            theirs.add_edge(u, v)
        yield ours, theirs, ids, rng


def test_order_and_ancestors_match_networkx():
    for ours, theirs, ids, rng in _random_graphs(300, acyclic=True):
        assert ours.find_cycle() is None
        assert ours.topological_order() == list(nx.lexicographical_topological_sort(theirs))
        subset = rng.sample(ids, rng.randint(0, len(ids))) + ["not_a_node"]
        expected = list(nx.lexicographical_topological_sort(theirs.subgraph(subset)))
        assert ours.topological_order(subset) == expected
        for node in ids:
            assert ours.ancestors(node) == nx.ancestors(theirs, node)


def test_a_cycle_is_found_exactly_when_there_is_one():
    found = 0
    for ours, theirs, _, _ in _random_graphs(300, acyclic=False):
        cycle = ours.find_cycle()
        assert (cycle is None) == nx.is_directed_acyclic_graph(theirs)
        if cycle is not None:
            found += 1
            assert cycle[0] == cycle[-1] and len(set(cycle)) == len(cycle) - 1
            assert all(theirs.has_edge(u, v) for u, v in zip(cycle, cycle[1:]))
    assert found > 50
