"""What a recipe will cost, known before any work: each node type estimates its own cost from its parameters and
its inputs' estimates (``NodeSpec.cost``, declared with ``estimated_by``), and the engine walks the graph in order
and sums.

A node's ``Cost`` says what its outputs carry (``elements``: how many elements flow on, so a placement's count reaches
the simulation through the nodes that turn, mix and cull it; ``inscribed``, ``volume``: an element library's smallest
inscribed radius and mean volume, for a placement whose r comes from its elements; ``faces``: mesh faces per element,
what a renderer holds) and what its work spends (``particles`` simulated, ``seconds`` of CPU, ``memory`` held at its
peak), its levers (``time_lever``, ``memory_lever``: the parameter that brings its seconds or its memory down), and
``over``: its own rules of what a run does not start on unasked. One rule weighs every node's estimate (``limit_over``):
CPU seconds over the run's ``--max-minutes`` and a peak over the memory the machine has available are refused at the
node's lever, with the value that stays under. The run's peak memory is the process's own (``PROCESS_BYTES``) and the
largest node's. A node type with no ``cost`` carries nothing on and spends nothing worth saying. ``nodegraph check``
prints the sum and refuses what is over (``--yes`` passes what a run would start with ``--yes``); ``run`` does the same
before its first node.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .context import format_seconds
from .node import NodeSpec

# bytes a run's process holds before any node's work: Python with numpy and the engine loaded (each node's
# ``memory`` is on top of it): `python -c "import nodegraph.cli, numpy, resource; print(resource.getrusage(
# resource.RUSAGE_SELF).ru_maxrss)"` prints 48,564 KiB (2 cores, load 11, 2026-12-06)
PROCESS_BYTES = 48 * 2**20
# CPU seconds per mesh face of the elements (faces per element × elements) of the steps that say nothing of their own
# time (placing, refining, the contact dents, measuring, exporting): what the scene table's runs spent outside their
# simulations and pictures, 4.7–9.5 µs a face in seven of its eight recipes (22 µs in the one with a draped slab on
# top; benchmarks/measured/scenes.jsonl); where the faces are not known, OTHER_CPU_PER_ELEMENT (their 3–13 ms an
# element): the estimate's ``time`` line
OTHER_CPU_PER_FACE = 6e-6
OTHER_CPU_PER_ELEMENT = 0.010
# CPU seconds of each step that says nothing of its own time, whatever its elements (its inputs read and hashed, its
# result stored and recorded), and of a run's start before its first step (imports, the recipe loaded and checked):
# a draft's steps are mostly these. The cold --draft runs of the main job (63 such steps: 6.9 CPU s, 0.025 a step
# beyond its faces' share) and of a second recipe (38: 3.6 CPU s, 0.09 a step) spent 1.9 and 1.6 CPU s before their
# steps (their closing tables; 2 cores, load 7-10); the drafts' runs against the estimate: benchmarks/measured/
# cost.jsonl
OTHER_CPU_PER_STEP = 0.05
START_CPU = 2.0
# what the time line leaves out: the rates above are an idle machine's; where other work holds the cores, the threads
# of the simulations and the preview wait for them and spend more CPU (the main job's draft, 21 CPU s estimated:
# 23.3 spent on two threads at load 1.2-2.3, 31.3 at load 5.5, its simulations 11.1 of them against 3.4; 22.3 on one
# thread at load 4.5; benchmarks/measured/cost.jsonl)
IDLE_RATES = "at an idle machine's rates (on a busy one the simulations' and preview's threads spend more)"


MEMINFO = "/proc/meminfo"  # where Linux says the memory a new process can take without swapping (MemAvailable)


def available_memory() -> int | None:
    """Bytes of memory this machine has available now (MemAvailable); None where the system does not say."""
    try:
        found = re.search(r"^MemAvailable:\s+(\d+) kB", Path(MEMINFO).read_text(), re.M)
    except OSError:
        return None
    return int(found.group(1)) * 1024 if found else None


@dataclass(frozen=True)
class Limits:
    """The limits a run enforces that a node's estimate is weighed against (``--max-minutes``, the machine's
    available memory), and what it runs."""

    max_seconds: float | None = 600.0  # a node's own CPU seconds above this is refused unless --yes
    max_bytes: int | None = None  # a peak above this is refused unless --yes (a run's: ``available_memory()``)
    outputs: tuple[str, ...] | None = None  # the nodes a run asks for (``--output``): those and what they need are
    # weighed (None: the recipe's outputs, as ``check`` weighs them)


@dataclass(frozen=True)
class Lever:
    """The parameter that brings a node's CPU seconds (or its memory) down, and ``allowed(budget)``: in words, the
    values that keep them within ``budget`` seconds (or bytes above ``PROCESS_BYTES``): "frames ≤ 1,234"."""

    param: str
    allowed: Callable[[float], str]


@dataclass(frozen=True)
class Cost:
    """One node's estimate (every field optional: 0 or None where the node has nothing to say)."""

    elements: int | None = None  # elements its outputs carry on (None: not known from the recipe)
    inscribed: float | None = None  # mm: the smallest inscribed radius of the elements its outputs are made of
    volume: float | None = None  # mm³: the mean volume of the elements its outputs are made of
    elongation: float | None = None  # the largest length over width of the elements its outputs are made of
    faces: float | None = None  # mesh faces per element its outputs carry (a mean over them)
    kinds: tuple[str, ...] = ()  # the element kinds its outputs carry, where a library names them (a cull's share)
    made: int = 0  # elements it makes (a placement)
    particles: int = 0  # particles it simulates
    seconds: float = 0.0  # CPU seconds of its work
    memory: int = 0  # bytes it holds at its peak, above ``PROCESS_BYTES``
    what: str = ""  # its work in words ("15 frames × 10 substeps × 2 iterations of 15,424 particles")
    over: tuple[tuple[str, str, bool], ...] = ()  # (parameter, message, passes with --yes): its own rules
    time_lever: Lever | None = None  # what brings ``seconds`` down (``limit_over`` names it)
    memory_lever: Lever | None = None  # what brings ``memory`` down


@dataclass(frozen=True)
class CostQuery:
    """What a node's ``cost`` function receives: its id and parameters, its inputs' estimates by port (one per wire),
    every node of the recipe (``NodeEntry`` by id, to weigh a shape it fills), the run's limits and the recipe's
    effects."""

    node_id: str
    params: Mapping[str, Any]
    inputs: Mapping[str, list[Cost]]
    nodes: Mapping[str, Any]
    limits: Limits
    effects: frozenset[str] = frozenset()

    def elements(self, port: str) -> int | None:
        """The elements the wires into ``port`` carry, summed; None when one of them is not known."""
        counts = [c.elements for c in self.inputs.get(port, [])]
        return None if not counts or None in counts else sum(counts)

    def faces(self, port: str) -> float | None:
        """Faces per element over the wires into ``port``: weighted by their elements where they carry some, else a
        plain mean (a library's variants); None when none says."""
        said = [c for c in self.inputs.get(port, []) if c.faces is not None]
        if not said:
            return None
        if all(c.elements for c in said):
            return sum(c.faces * c.elements for c in said) / sum(c.elements for c in said)
        return sum(c.faces for c in said) / len(said)

    def inscribed(self, port: str) -> float | None:
        """The smallest inscribed radius among the wires into ``port`` (None when none says)."""
        radii = [c.inscribed for c in self.inputs.get(port, []) if c.inscribed is not None]
        return min(radii) if radii else None

    def elongation(self, port: str) -> float | None:
        """The largest length over width among the wires into ``port`` (None when none says)."""
        ratios = [c.elongation for c in self.inputs.get(port, []) if c.elongation is not None]
        return max(ratios) if ratios else None

    def volume(self, port: str) -> float | None:
        """The mean element volume over the wires into ``port`` (None when one of them does not say)."""
        volumes = [c.volume for c in self.inputs.get(port, [])]
        return None if not volumes or None in volumes else sum(volumes) / len(volumes)

    def kinds(self, port: str) -> tuple[str, ...]:
        """The element kinds the wires into ``port`` carry, in order, each once (empty where none says)."""
        return tuple(dict.fromkeys(k for c in self.inputs.get(port, []) for k in c.kinds))


def estimated_by(cost: Callable[[CostQuery], Cost]) -> Callable[[NodeSpec], NodeSpec]:
    """Declare a node type's estimate, above its ``@node``: ``cost(query)`` gives its ``Cost`` from its parameters
    and its inputs' estimates (a ``CostQuery``), before any work::

        @estimated_by(passes("placement"))
        @node("rotate", ...)
        def rotate(ctx, placement, ...): ...
    """

    def wrap(spec: NodeSpec) -> NodeSpec:
        return dataclasses.replace(spec, cost=cost)

    return wrap


def passes(
    port: str, share: float | Callable[[tuple[str, ...]], float] = 1.0, faces: str | None = None
) -> Callable[[CostQuery], Cost]:
    """A ``cost`` for a node whose output carries the elements of input ``port`` (× ``share``: a cull's kept
    share, or a function of the element kinds that gives it), with the faces per element, the kinds, the smallest
    inscribed radius, the mean volume and the elongation of input ``faces`` (default ``port``: the meshes a
    placement gets from the libraries it is mixed with), and whose own work is small."""

    def cost(q: CostQuery) -> Cost:
        count = q.elements(port)
        kinds = q.kinds(faces or port)
        kept = share(kinds) if callable(share) else share
        return Cost(
            elements=None if count is None else int(round(count * kept)),
            inscribed=q.inscribed(faces or port),
            volume=q.volume(faces or port),
            elongation=q.elongation(faces or port),
            faces=q.faces(faces or port),
            kinds=kinds,
        )

    return cost


@dataclass
class Estimate:
    """A recipe's estimate: each node's ``Cost`` and the sums ``check`` prints."""

    costs: dict[str, Cost] = field(default_factory=dict)
    family: dict[str, int] = field(default_factory=dict)  # instances of a variant family's node
    outputs: tuple[str, ...] = ()  # the nodes whose outputs the recipe asks for
    compiles: bool = True  # whether a run may compile kernels (``compile_ahead.kernels_due``), said beside the time
    limits: Limits = field(default_factory=Limits)  # what ``over`` weighs each node against

    @property
    def elements(self) -> int | None:
        """The elements the recipe's outputs carry (the largest of them: a scene, its export and its preview
        carry the same ones); None when none is known."""
        counts = [self.costs[n].elements for n in self.outputs if self.costs[n].elements is not None]
        return max(counts) if counts else None

    @property
    def particles(self) -> int:
        return sum(c.particles for c in self.costs.values())

    @property
    def seconds(self) -> float:
        """CPU seconds of the work the nodes estimate (each instance of a family once)."""
        return sum(c.seconds * self.family.get(n, 1) for n, c in self.costs.items())

    @property
    def other_seconds(self) -> float:
        """CPU seconds of the steps that do not estimate their own: ``OTHER_CPU_PER_STEP`` each and
        ``OTHER_CPU_PER_FACE`` for each face of the elements of the recipe's outputs (``OTHER_CPU_PER_ELEMENT`` an
        element where their faces are not known)."""
        elements = self.elements or 0
        faces = [c.faces for c in (self.costs[n] for n in self.outputs) if c.elements == elements and c.faces]
        steps = sum(self.family.get(n, 1) for n, c in self.costs.items() if not c.seconds)
        per_element = OTHER_CPU_PER_FACE * max(faces) if faces else OTHER_CPU_PER_ELEMENT
        return steps * OTHER_CPU_PER_STEP + elements * per_element

    @property
    def cpu_seconds(self) -> float:
        """CPU seconds of the whole run: its start (``START_CPU``), what the nodes estimate (``seconds``) and
        ``other_seconds``."""
        return START_CPU + self.seconds + self.other_seconds

    @property
    def peak(self) -> tuple[int, str | None]:
        """(bytes, node): the process's peak, at the node holding the most."""
        node = max(self.costs, key=lambda n: self.costs[n].memory, default=None)
        held = self.costs[node].memory if node is not None else 0
        return PROCESS_BYTES + held, node if held else None

    def over(self) -> list[tuple[str, str | None, str, bool]]:
        """(node, parameter, message, passes with --yes) of every request beyond a limit: the nodes' own rules and
        the run's limits on time and memory (``limit_over``)."""
        own = [(n, p, m, yes) for n, c in self.costs.items() for p, m, yes in c.over]
        return own + [(n, p, m, True) for n, c in self.costs.items() for p, m in limit_over(c, self.limits, self.made)]

    @property
    def made(self) -> str:
        """The nodes that made the elements, with how many each ("egg_place 23,447, rice_place 1,639")."""
        return ", ".join(f"{n} {c.made:,}" for n, c in self.costs.items() if c.made)

    def lines(self) -> list[str]:
        """The estimate in words, a line each: elements, the simulations, memory."""
        out = []
        elements = self.elements
        made = self.made
        known = f"≈ {elements:,}" if elements is not None else "not known from the recipe alone"
        out.append(f"elements: {known}" + (f", kept of those placed ({made})" if made else ""))
        sims = [(n, c) for n, c in self.costs.items() if c.particles]
        for node_id, c in sims:
            out.append(f"{node_id}: {c.what or f'{c.particles:,} particles'}, ≈ {minutes(c.seconds)} CPU")
        if len(sims) > 1:
            out.append(f"simulations: {self.particles:,} particles, ≈ {minutes(sum(c.seconds for _, c in sims))} CPU")
        peak, node = self.peak
        at = f" (at {node}: {gib(self.costs[node].memory)} of it)" if node else ""
        out.append(f"peak memory: ≈ {gib(peak)}{at}")
        out.append(self.time_line())
        return out

    def time_line(self) -> str:
        """The run's CPU time in words, by simulations, pictures (the other nodes that estimate their seconds) and
        the rest (``other_seconds``)."""
        family = lambda n: self.family.get(n, 1)
        sims = sum(c.seconds * family(n) for n, c in self.costs.items() if c.particles)
        pictures = self.seconds - sims
        other = self.other_seconds
        parts = [f"{what} {minutes(s)}" for what, s in (("simulations", sims), ("pictures", pictures)) if s >= 0.5]
        parts.append(f"other steps {minutes(other)}")
        parts.append(f"start {minutes(START_CPU)}")
        compiling = "; its kernels are not compiled yet: a run compiles them first" if self.compiles else ""
        return f"time: ≈ {minutes(self.cpu_seconds)} CPU ({', '.join(parts)}), {IDLE_RATES}" + compiling


def limit_over(cost: Cost, limits: Limits, made: str = "") -> list[tuple[str | None, str]]:
    """(parameter, message) of each run limit a node's estimate is over: its CPU seconds over ``max_seconds``, the
    process's peak at it over ``max_bytes``; named at its lever with the values that stay under (at the node itself,
    parameter None, when it has none), the nodes that made the elements (``made``) beside a memory over. The one
    rule for every node: a run starts on neither unasked (``--yes``)."""
    what = cost.what or "its work"
    out = []
    if limits.max_seconds is not None and cost.seconds > limits.max_seconds:
        lever = cost.time_lever
        allowed = f"; allowed: {lever.allowed(limits.max_seconds)}" if lever else ""
        message = (
            f"{what} would take ≈ {format_seconds(cost.seconds)} of CPU, over a run's limit of "
            f"{format_seconds(limits.max_seconds)} (--max-minutes){allowed}"
        )
        out.append((lever.param if lever else None, message))
    peak = PROCESS_BYTES + cost.memory
    if limits.max_bytes is not None and peak > limits.max_bytes:
        lever = cost.memory_lever
        allowed = f"; allowed: {lever.allowed(limits.max_bytes - PROCESS_BYTES)}" if lever else ""
        elements = f"; the elements it holds were made by {made}" if made and cost.elements else ""
        message = (
            f"{what} would hold ≈ {gib(peak)} at its peak, over the {gib(limits.max_bytes)} this machine has "
            f"available{allowed}{elements}"
        )
        out.append((lever.param if lever else None, message))
    return out


def minutes(seconds: float) -> str:
    if seconds < 0.5:
        return "< 1 s"
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.1f} min"


def gib(size: float) -> str:
    return f"{size / 2**30:.2f} GiB" if size >= 2**30 else f"{size / 2**20:,.0f} MiB"


def estimate(
    nodes: Mapping[str, Any],
    order: list[str],
    outputs: list[str],
    limits: Limits,
    effects: frozenset[str] = frozenset(),
) -> Estimate:
    """Walk ``order`` (every node after those it reads), asking each node type's ``cost`` with its inputs'
    estimates; ``nodes``: ``NodeEntry`` by id, ``outputs``: the node ids the recipe asks for, ``effects``: the
    recipe's."""
    result = Estimate(outputs=tuple(dict.fromkeys(outputs)), limits=limits)
    for node_id in order:
        entry = nodes[node_id]
        inputs = {port: [result.costs[w.node] for w in wires] for port, wires in entry.inputs.items()}
        spec_cost = entry.spec.cost
        query = CostQuery(node_id, entry.params, inputs, nodes, limits, effects)
        result.costs[node_id] = spec_cost(query) if spec_cost is not None else Cost()
        if entry.family:
            result.family[node_id] = entry.family
    return result
