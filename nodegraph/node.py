"""Node type declarations: typed ports, parameters and effects, readable as data.

A node module declares a node with the ``@node`` decorator around a plain function::

    @node("decimate",
          inputs={"mesh": In(Mesh, "the mesh to simplify")},
          outputs={"mesh": Out(Mesh, "the simplified mesh")},
          params={"faces": Param(int, 1000, "target face count", range=(4, 10_000_000))})
    def decimate(ctx, mesh, *, faces): ...

The decorator returns a ``NodeSpec``; the registry finds specs by scanning module attributes,
so declaring a node has no side effect and there is no global registry. A node's cached results are
keyed on the code it runs (``code_digest``: its modules and the engine's) and on the versions of the libraries
that code imports, so editing it, a helper it imports or the engine, or upgrading a library it uses, re-runs it;
there is no version to bump by hand.
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from .context import Context
from .errors import NodeDeclarationError
from .params import Param, ParamValueError, resolve

# Keyword arguments of ``NodeSpec.call``; no port or parameter may take these names.
CALL_ARGUMENTS = frozenset({"seed", "effects"})


@dataclass(frozen=True)
class In:
    """An input port. ``many=True`` takes a list: several wires, or every variant of a family."""

    type: type
    doc: str = ""
    optional: bool = False
    many: bool = False

    @property
    def type_name(self) -> str:
        name = self.type.__name__
        return f"list[{name}]" if self.many else name


@dataclass(frozen=True)
class Out:
    """An output port; ``columns``: a Table output's columns, where they are known before it runs (a sweep's metric
    naming one is checked against them before any work)."""

    type: type
    doc: str = ""
    columns: tuple[str, ...] = ()

    @property
    def type_name(self) -> str:
        return self.type.__name__


@dataclass(frozen=True)
class Moved:
    """Where a parameter the node no longer has now lives: parameter ``param`` of the node wired into this
    node's input ``input`` (a node of type ``node_type``). Validation says so where a recipe still sets it."""

    input: str
    param: str
    node_type: str

    def advice(self, old: str) -> str:
        return (
            f"parameter '{old}' moved to parameter '{self.param}' of the {self.node_type} node wired into input "
            f"'{self.input}'"
        )


@dataclass(frozen=True)
class NodeSpec:
    """Everything the engine knows about a node type; ``run`` is the implementation."""

    type_name: str
    doc: str
    run: Callable[..., Any]
    inputs: Mapping[str, In] = field(default_factory=dict)
    outputs: Mapping[str, Out] = field(default_factory=dict)
    params: Mapping[str, Param] = field(default_factory=dict)
    effects: frozenset[str] = frozenset()
    random: bool = False
    check: Callable[[dict[str, Any]], list[tuple[str, str]]] | None = None
    module: str = ""
    moved: Mapping[str, Moved] = field(default_factory=dict)
    check_recipe: Callable[[str, Mapping[str, Any]], list[tuple[str, str]]] | None = None
    overlap: bool | Callable[[], None] = False
    libraries: Callable[[], None] | None = None  # loads the native libraries its run opens (``loads_libraries``)
    check_work: Callable[[str, Mapping[str, Any]], list[tuple[str, str, bool]]] | None = None
    store: bool = True  # False: its outputs never go into the cache; computed again where needed (``node``)
    cost: Callable[[Any], Any] | None = None  # its estimate from its parameters and inputs' (``cost.estimated_by``)
    warns: Callable[[str, Mapping[str, Any]], list[tuple[str, str]]] | None = None  # ``warns_of``

    def __call__(self, ctx: Any, **kwargs: Any) -> Any:
        """Call the implementation with a context and arguments as given: nothing is checked or filled in."""
        return self.run(ctx, **kwargs)

    def call(self, *, seed: int = 0, effects: Iterable[str] = (), **given: Any) -> Any:
        """Run the node outside a recipe, as the executor would: ``given`` names inputs and parameters.

        Parameters are validated, defaults filled in and ``check`` applied (ParamValueError); an input
        not given is passed as an unwired port is (None, or [] for a many-input). ``seed`` becomes
        ``ctx.seed`` of a random node (others get None, as in a recipe); ``effects`` are the effects the
        node receives in ``ctx.effects``. Returns what the implementation returns. For tests, scripts
        and benchmarks: ``decimate.call(mesh=m, faces=500)``, ``scatter.call(seed=3, mesh=m)``.
        """
        where = f"node type '{self.type_name}'"
        unknown = sorted(set(given) - set(self.inputs) - set(self.params))
        moved = [self.moved[name].advice(name) for name in unknown if name in self.moved]
        if moved:
            raise TypeError(f"{where}: " + "; ".join(moved))
        if unknown:
            raise TypeError(
                f"{where} has no input or parameter {unknown}; inputs: {sorted(self.inputs)}, "
                f"parameters: {sorted(self.params)}"
            )
        missing = [name for name, port in self.inputs.items() if not port.optional and name not in given]
        missing += [name for name, param in self.params.items() if param.required and name not in given]
        if missing:
            raise TypeError(f"{where} needs {missing}")
        effects = frozenset(effects)
        if not effects <= self.effects:
            raise ValueError(
                f"{where} does not implement the effects {sorted(effects - self.effects)}; "
                f"it implements {sorted(self.effects)}"
            )
        params = self.resolve_params({name: value for name, value in given.items() if name in self.params})
        problems = self.check(dict(params)) if self.check is not None else []
        if problems:
            raise ParamValueError(
                f"{where}: " + "; ".join(f"{name}: {message}" for name, message in problems),
                f"see `nodegraph describe {self.type_name}`",
            )
        inputs = {name: given.get(name, [] if port.many else None) for name, port in self.inputs.items()}
        ctx = Context.standalone(node_type=self.type_name, seed=seed if self.random else None, effects=effects)
        return self.run(ctx, **inputs, **params)

    def resolve_params(self, given: Mapping[str, Any]) -> dict[str, Any]:
        """Validated parameters with defaults filled in (raises ParamValueError / KeyError)."""
        return resolve(self.params, given)


def node(
    type_name: str,
    *,
    outputs: Mapping[str, Out],
    inputs: Mapping[str, In] | None = None,
    params: Mapping[str, Param] | None = None,
    effects: tuple[str, ...] | frozenset[str] = (),
    random: bool = False,
    check: Callable[[dict[str, Any]], list[tuple[str, str]]] | None = None,
    moved: Mapping[str, Moved] | None = None,
    check_recipe: Callable[[str, Mapping[str, Any]], list[tuple[str, str]]] | None = None,
    overlap: bool | Callable[[], None] = False,
    check_work: Callable[[str, Mapping[str, Any]], list[tuple[str, str, bool]]] | None = None,
    store: bool = True,
) -> Callable[[Callable[..., Any]], NodeSpec]:
    """Declare a node type around its implementation ``fn(ctx, **inputs, **params)``, whose docstring is the node's
    doc.

    The node's cache key covers the code it runs and the libraries' versions (``code_digest``), so nothing is
    bumped by hand when either changes. ``effects`` are the physical
    effects the node implements; at run time ``ctx.effects`` holds only those the recipe asked for.
    ``random`` nodes get ``ctx.rng`` and the seed enters their cache key; others cannot draw random
    numbers. ``check(params)`` returns ``[(param, message), ...]`` for constraints between parameters.
    ``moved`` names parameters the node no longer has and where each now lives (``Moved``), so a recipe
    that still sets one is told where. ``check_recipe(node_id, nodes)`` checks the node against the rest of
    a valid recipe (``nodes``: every node's ``NodeEntry`` by id) and returns ``[(param, message), ...]``
    for contradictions between nodes. ``check_work(node_id, nodes)``, the same for what takes a moment to
    check (a shape's mesh made to weigh a placement against it), as ``[(param, message, yes), ...]``, ``yes``: a
    request larger than a run should start on unasked, which ``--yes`` passes; ``nodegraph check`` runs it, and
    ``run`` before any work when the node's result is not cached (``load_recipe(work=True)``). ``overlap``: the
    node's work is native code that releases the GIL (a renderer's own threads) and it launches no numba kernel,
    so a run may compute the instances that neither need it nor depend on it in a second thread while it runs
    (``executor.Beside``). A callable ``overlap`` is called in
    the main thread before that second thread starts: it loads every native library the node will load, so the node
    never calls ``dlopen`` while the other thread may be in one (the loader's lock against the GIL: a library whose
    initialiser drops and retakes the GIL, as USD's does, deadlocked against Mitsuba loading a plugin).
    A node that may run in that second thread declares its own libraries the same way, above its ``@node`` with
    ``loads_libraries`` (the export: USD's).
    ``store=False``: the node's outputs are cheaper to compute again from its cached inputs than to store and load
    (large values made in a moment: a scene description, files' bytes), so they never go into the cache, where they
    would fill its limit and push out what is dear to compute; a run computes the node again where its outputs are
    needed (an output asked for, a step downstream that runs, a recording to fill). A node's estimate of what it
    makes and spends is declared above its ``@node`` with ``@nodegraph.cost.estimated_by(cost)``.
    """
    inputs = dict(inputs or {})
    params = dict(params or {})

    def wrap(fn: Callable[..., Any]) -> NodeSpec:
        clash = set(inputs) & set(params)
        if clash:
            raise NodeDeclarationError(f"{type_name}: names used both as input and parameter: {sorted(clash)}")
        reserved = (set(inputs) | set(params)) & CALL_ARGUMENTS
        if reserved:
            raise NodeDeclarationError(
                f"{type_name}: {sorted(reserved)} cannot name an input or parameter "
                "(the seed and the effects come from the recipe, in ctx)"
            )
        if not outputs:
            raise NodeDeclarationError(f"{type_name}: a node needs at least one output port")
        signature = inspect.signature(fn)
        accepts_kwargs = any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values())
        if not accepts_kwargs:
            missing = (set(inputs) | set(params)) - set(signature.parameters)
            if missing:
                raise NodeDeclarationError(f"{type_name}: function {fn.__name__} lacks arguments {sorted(missing)}")
        for port in list(inputs.values()) + list(outputs.values()):
            if not isinstance(port.type, type):
                raise NodeDeclarationError(f"{type_name}: port type {port.type!r} is not a class")
        text = (inspect.getdoc(fn) or "").strip()
        return NodeSpec(
            type_name=type_name,
            doc=text,
            run=fn,
            inputs=MappingProxyType(inputs),
            outputs=MappingProxyType(dict(outputs)),
            params=MappingProxyType(params),
            effects=frozenset(effects),
            random=random,
            check=check,
            module=fn.__module__,
            moved=MappingProxyType(dict(moved or {})),
            check_recipe=check_recipe,
            overlap=overlap,
            check_work=check_work,
            store=store,
        )

    return wrap


def warns_of(find: Callable[[str, Mapping[str, Any]], list[tuple[str, str]]]) -> Callable[[NodeSpec], NodeSpec]:
    """Declare, above a node's ``@node``, what its run will warn of (``Context.warn``) that the recipe alone decides,
    such as a user's mesh file it repairs: ``find(node_id, nodes)`` → ``[(param, message), ...]`` (``nodes``: every
    node's ``NodeEntry`` by id); ``nodegraph check`` prints each at the parameter's file:line."""

    def wrap(spec: NodeSpec) -> NodeSpec:
        return dataclasses.replace(spec, warns=find)

    return wrap


def loads_libraries(load: Callable[[], None]) -> Callable[[NodeSpec], NodeSpec]:
    """Declare, above a node's ``@node``, what loads the native libraries its run opens: a run calls ``load`` in the
    main thread before it starts a second thread that computes the node beside an ``overlap`` node, so neither
    thread opens a library while the other may (the loader's lock against the GIL: USD's initialiser drops and
    retakes the GIL, and an export opening USD beside a renderer hung runs)."""

    def wrap(spec: NodeSpec) -> NodeSpec:
        return dataclasses.replace(spec, libraries=load)

    return wrap
