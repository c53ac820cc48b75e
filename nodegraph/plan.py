"""Planning a run before anything executes: the node instances the outputs need, where each input comes
from, each instance's seed and its cache key; and, for a pool of workers, the jobs.

Each node instance (a node, or one variant of a variant family) has a cache key that covers the node
type, a digest of the code it runs (``code_digest.node_code_digest``: its modules, the project's and the
engine's, that they import), the installed versions of the third-party libraries that code imports
(``code_digest.node_libraries``), the canonical parameters, the keys of the upstream values, the derived
seed (random nodes only), the requested effects the node implements and the bytes of the files its file
parameters name. Keys depend on upstream *keys*, not values, so the whole run is planned before anything
loads. The executor and the pools (``pool``, ``dask_pool``) both plan through this module.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from .cache import Cache
from .code_digest import node_code_digest, node_libraries
from .errors import NodegraphError
from .node_packages import node_package_names
from .params import canonical
from .recipe import NodeEntry, Recipe, Wire

# 2: the domain value types moved from nodegraph.values to nodes.values (stored type names); 3: keys cover the engine's
# code and the libraries' versions, no declared node version
CACHE_FORMAT = 3


@dataclass(frozen=True, order=True)
class Instance:
    """A node, or one variant of a node that is a variant family."""

    node: str
    variant: int | None = None

    @property
    def label(self) -> str:
        return self.node if self.variant is None else f"{self.node}[{self.variant}]"

    @property
    def entity(self) -> str:
        return f"/{self.node}" if self.variant is None else f"/{self.node}/{self.variant}"


def file_digests(entry: NodeEntry) -> dict[str, str]:
    """sha256 of the file each ``Param(file=True)`` of the node names (validation saw it exist)."""
    out = {}
    for name, param in entry.spec.params.items():
        value = entry.params.get(name)
        if param.file and value:
            path = Path(value)
            out[name] = hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else "missing"
    return out


def derive_seed(base: int, node_id: str, variant: int | None) -> int:
    """A 63-bit seed per node instance, so variants and sibling nodes draw independent streams."""
    digest = hashlib.sha256(f"{base}/{node_id}/{variant}".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


class Plan:
    """The instances, input sources, seeds and cache keys of one recipe's nodes (``keys`` fills as
    ``add`` plans nodes)."""

    def __init__(self, recipe: Recipe):
        self.recipe = recipe
        self.keys: dict[Instance, str] = {}
        self._packages: set[str] | None = None  # the installed node packages: the project code digests follow

    def instances(self, node_id: str) -> list[Instance]:
        family = self.recipe.nodes[node_id].family
        return [Instance(node_id)] if family is None else [Instance(node_id, v) for v in range(family)]

    def sources(self, inst: Instance) -> dict[str, list[tuple[Instance, str]]]:
        """Upstream (instance, port) pairs per input port: gathered for many-ports, mapped otherwise."""
        entry = self.recipe.nodes[inst.node]
        sources = {}
        for port_name, wires in entry.inputs.items():
            pairs = []
            for wire in wires:
                if entry.spec.inputs[port_name].many or self.recipe.nodes[wire.node].family is None:
                    pairs.extend((src, wire.port) for src in self.instances(wire.node))
                else:
                    pairs.append((Instance(wire.node, inst.variant), wire.port))
            sources[port_name] = pairs
        return sources

    def seed(self, inst: Instance) -> int | None:
        """The instance's derived seed; None for a node that draws no random numbers."""
        entry = self.recipe.nodes[inst.node]
        if not entry.spec.random:
            return None
        base = self.recipe.seed if entry.seed is None else entry.seed
        return derive_seed(base, entry.id, inst.variant)

    def add(self, node_ids) -> list[Instance]:
        """Plan every instance of the given nodes and of the nodes they need; returns them in
        topological order, each with its cache key in ``keys``."""
        order = []
        for node_id in self.recipe.order(sorted(self.recipe.upstream(set(node_ids)))):
            entry = self.recipe.nodes[node_id]
            for inst in self.instances(node_id):
                if inst not in self.keys:
                    self.keys[inst] = self._key(entry, inst)
                order.append(inst)
        return order

    def _node_packages(self) -> set[str]:
        if self._packages is None:
            self._packages = set(node_package_names())
        return self._packages

    def _key(self, entry: NodeEntry, inst: Instance) -> str:
        sources = sorted(self.sources(inst).items())
        payload = {
            "format": CACHE_FORMAT,
            "type": entry.spec.type_name,
            "code": node_code_digest(entry.spec, self._node_packages()),
            "libraries": node_libraries(entry.spec, self._node_packages()),
            "params": canonical(entry.params),
            "inputs": {port: [[self.keys[src], out] for src, out in pairs] for port, pairs in sources},
            "seed": self.seed(inst),
            "effects": sorted(entry.spec.effects & self.recipe.effects),
        }
        files = file_digests(entry)
        if files:  # only then: keys of nodes without file parameters stay as they were
            payload["files"] = files
        blob = json.dumps(payload, sort_keys=True, separators=(",", ":")).encode()
        return hashlib.sha256(blob).hexdigest()


# jobs for a pool of workers ------------------------------------------------------------------------


@dataclass(frozen=True)
class RecipeRef:
    """How a worker loads the same validated recipe: file, ``--set`` texts, plugin files, expected digest."""

    path: str
    overrides: tuple[str, ...]
    plugins: tuple[str, ...]
    digest: str

    @classmethod
    def of(cls, recipe: Recipe, plugins=()) -> RecipeRef:
        if not Path(recipe.path).is_file():
            raise NodegraphError(
                f"recipe {recipe.path} is not a file: a worker loads the recipe from its file, so a pool needs one"
            )
        return cls(
            str(Path(recipe.path).resolve()),
            tuple(recipe.overrides),
            tuple(str(Path(p).resolve()) for p in plugins),
            recipe.digest(),
        )


@dataclass(frozen=True)
class Job:
    """One node instance to compute: its cache key, where it is in which recipe, the keys it waits for."""

    key: str
    label: str
    recipe: RecipeRef
    node: str
    variant: int | None
    needs: tuple[str, ...]
    max_seconds: float | None = None


def plan_jobs(recipe: Recipe, wires: list[Wire], cache: Cache, ref: RecipeRef, max_seconds=None) -> list[Job]:
    """Jobs for every instance the outputs need that the cache does not hold yet, in topological order; those of
    nodes never cached (``NodeSpec.store``: a worker's result reaches the run only through the cache) and those that
    need one are left to the run itself."""
    plan = Plan(recipe)
    order = plan.add({w.node for w in wires})
    missing = {inst for inst in order if not cache.has(plan.keys[inst])}
    here: set[Instance] = set()
    for inst in order:
        sources = {src for pairs in plan.sources(inst).values() for src, _ in pairs}
        if not recipe.nodes[inst.node].spec.store or sources & here:
            here.add(inst)
    jobs = []
    for inst in order:
        if inst not in missing or inst in here:
            continue
        needs = sorted({plan.keys[src] for pairs in plan.sources(inst).values() for src, _ in pairs if src in missing})
        jobs.append(Job(plan.keys[inst], inst.label, ref, inst.node, inst.variant, tuple(needs), max_seconds))
    return jobs


__all__ = ["CACHE_FORMAT", "Instance", "Job", "Plan", "RecipeRef", "derive_seed", "file_digests", "plan_jobs"]
