"""The recipe's wiring as a directed graph of node ids: the few graph operations a run needs (upstream
nodes, a deterministic topological order, a cycle to report), without loading a graph library (importing
networkx cost about a third of the engine's import time, paid by every run, a cached re-run included)."""

from __future__ import annotations

import heapq


class Dag:
    """Node ids and the wires between them (an edge u → v: v takes an input from u)."""

    def __init__(self, nodes=()):
        self._succ: dict[str, dict[str, None]] = {}  # dicts as ordered sets: every walk is deterministic
        self._pred: dict[str, dict[str, None]] = {}
        for node in nodes:
            self.add_node(node)

    def add_node(self, node: str) -> None:
        self._succ.setdefault(node, {})
        self._pred.setdefault(node, {})

    def add_edge(self, source: str, target: str) -> None:
        self.add_node(source)
        self.add_node(target)
        self._succ[source][target] = None
        self._pred[target][source] = None

    def __contains__(self, node) -> bool:
        return node in self._succ

    def ancestors(self, node: str) -> set[str]:
        """Every node ``node`` depends on, directly or not (not itself)."""
        seen: set[str] = set()
        pending = list(self._pred[node])
        while pending:
            current = pending.pop()
            if current not in seen:
                seen.add(current)
                pending += self._pred[current]
        return seen

    def topological_order(self, nodes=None) -> list[str]:
        """``nodes`` (default: all) in dependency order, ties broken by the smaller id (as networkx's
        ``lexicographical_topological_sort``); ids not in the graph and edges leaving ``nodes`` are ignored."""
        chosen = set(self._succ) if nodes is None else {n for n in nodes if n in self._succ}
        waiting = {n: sum(p in chosen for p in self._pred[n]) for n in chosen}
        ready = [n for n, count in waiting.items() if count == 0]
        heapq.heapify(ready)
        order = []
        while ready:
            node = heapq.heappop(ready)
            order.append(node)
            for target in self._succ[node]:
                if target in chosen:
                    waiting[target] -= 1
                    if waiting[target] == 0:
                        heapq.heappush(ready, target)
        if len(order) != len(chosen):
            raise ValueError("the graph has a cycle")
        return order

    def find_cycle(self) -> list[str] | None:
        """One cycle as the ids along it, the first repeated at the end (depth-first from each node in the
        order added); None when there is none."""
        state: dict[str, int] = {}  # 1: on the current path, 2: done
        for root in self._succ:
            if root in state:
                continue
            path = [root]
            state[root] = 1
            stack = [iter(self._succ[root])]
            while stack:
                target = next(stack[-1], None)
                if target is None:
                    state[path.pop()] = 2
                    stack.pop()
                elif state.get(target) == 1:
                    return path[path.index(target) :] + [target]
                elif target not in state:
                    state[target] = 1
                    path.append(target)
                    stack.append(iter(self._succ[target]))
        return None
