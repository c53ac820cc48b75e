"""Recipes: YAML → validated graph of node instances. Every problem is collected before anything runs.

Structure is checked by pydantic models (``extra="forbid"``); their errors are mapped back to the
file's lines. Node types, parameters, wiring, port types, cycles, variant families, effects and
outputs are then checked against the registry, each issue with file:line:column and a suggestion.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from .dag import Dag
from .errors import Issue, Location, RecipeError
from .node import NodeSpec
from .output_folder import PLAIN_NAME, recipe_file_name
from .params import RECIPE_FILE_NAME, ParamValueError, canonical
from .registry import Registry
from .yaml_source import SourceMap, load_yaml, load_yaml_file

if TYPE_CHECKING:
    from .cost import Estimate, Limits
    from .sweep_decl import SweepDecl

NODE_ID = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
MAX_VARIANTS = 100_000


class NodeModel(BaseModel):
    """One node entry of a recipe."""

    model_config = ConfigDict(extra="forbid")
    type: str
    params: dict[str, Any] = Field(default_factory=dict)
    inputs: dict[str, str | list[str]] = Field(default_factory=dict)
    variants: int | None = Field(default=None, ge=1, le=MAX_VARIANTS)
    seed: int | None = None
    doc: str | None = None


class RecipeModel(BaseModel):
    """The top level of a recipe file."""

    model_config = ConfigDict(extra="forbid")
    name: str | None = None
    description: str | None = None
    seed: int = 0
    effects: list[str] = Field(default_factory=list)
    outputs: list[str] = Field(min_length=1)
    nodes: dict[str, Any] = Field(min_length=1)
    sweeps: dict[str, Any] = Field(default_factory=dict)  # checked by sweep_decl.check_sweeps
    draft: dict[str, Any] = Field(default_factory=dict)  # node.param → value that --draft applies


@dataclass(frozen=True)
class Wire:
    """A connection from ``node.port``."""

    node: str
    port: str

    def __str__(self) -> str:
        return f"{self.node}.{self.port}"


@dataclass
class NodeEntry:
    """A validated node of a recipe: its spec, resolved parameters and incoming wires per port."""

    id: str
    spec: NodeSpec
    params: dict[str, Any]
    inputs: dict[str, list[Wire]]
    variants: int | None = None
    seed: int | None = None
    family: int | None = None  # number of instances when this node is a variant family


@dataclass
class Recipe:
    """A validated recipe, ready for the executor."""

    name: str
    file_name: str  # what its outputs are named after (``output_folder.recipe_file_name``)
    path: str
    seed: int
    effects: frozenset[str]
    outputs: list[Wire]
    nodes: dict[str, NodeEntry]
    source: SourceMap
    graph: Dag = field(repr=False)
    overrides: tuple[str, ...] = ()  # the --set texts applied on top of the file
    sweeps: dict[str, SweepDecl] = field(default_factory=dict)  # the recipe's own sweeps (``nodegraph sweep``)
    draft: tuple[str, ...] = ()  # the draft: block as node.param=value texts (what --draft applies)
    cost: Estimate | None = None  # what it will cost (``nodegraph.cost``), weighed when loaded with ``work``
    warnings: tuple[Issue, ...] = ()  # what its nodes will warn of (``node.warns_of``), found when loaded with ``work``

    def digest(self) -> str:
        """sha256 of what the recipe computes (name, seed, effects, outputs, every node's type, parameters,
        variants and wires): two settings of one recipe differ, one setting run twice does not."""
        nodes = {
            node_id: {
                "type": e.spec.type_name,
                "params": canonical(e.params),
                "family": e.family,
                "inputs": {port: [str(w) for w in wires] for port, wires in sorted(e.inputs.items())},
            }
            for node_id, e in sorted(self.nodes.items())
        }
        text = json.dumps(
            {
                "name": self.name,
                "seed": self.seed,
                "effects": sorted(self.effects),
                "outputs": [str(w) for w in self.outputs],
                "nodes": nodes,
            },
            sort_keys=True,
        )
        return hashlib.sha256(text.encode()).hexdigest()

    def upstream(self, node_ids) -> set[str]:
        """The given nodes and every node they depend on (what a pull-based run must consider)."""
        needed = set(node_ids)
        for node_id in node_ids:
            needed |= self.graph.ancestors(node_id)
        return needed

    def order(self, node_ids=None) -> list[str]:
        """Nodes in a deterministic topological order (ties broken by id)."""
        return self.graph.topological_order(node_ids)


def nearest(word: str, options) -> str | None:
    matches = difflib.get_close_matches(str(word), [str(o) for o in options], n=1, cutoff=0.5)
    return matches[0] if matches else None


TYPO = 0.8  # a parameter name this close to an existing one of its node (difflib's ratio) is a typo of it
SUGGESTED = 2  # at most this many parameters of the recipe suggested for a name that is no typo
_SPELLINGS = {"colour": "color", "grey": "gray", "centre": "center", "metre": "meter"}


def _words(text: str) -> set[str]:
    """The words of a parameter name or doc, for matching: lower case, one spelling, a plural's 's' dropped."""
    words = set()
    for word in re.findall(r"[a-z]{3,}", text.lower()):
        word = _SPELLINGS.get(word, word)
        words.add(word[:-1] if len(word) > 4 and word.endswith("s") and not word.endswith("ss") else word)
    return words


def _one_or_more(names: tuple[str, ...]) -> str | tuple[str, ...] | None:
    return names[0] if len(names) == 1 else names or None


def nearest_params(node_id: str, key: str, params: dict[str, dict[str, str]]) -> tuple[str, ...]:
    """What an unknown parameter ``key`` of node ``node_id`` may have meant, among ``params`` (node: {parameter:
    doc}, the recipe's nodes): a typo of one of the node's own (``TYPO``); else those of any node whose name and doc
    share the most of its words (``shade.fruit_color``, when a fruit's colour follows ``ripen.days``, whose doc names
    both: that before ``shade.scenery_color``, which names one), each named ``node.param`` where one is not the
    node's own; else the node's own closest by spelling. Edit distance among the node's own names alone suggested
    ``scenery_color`` for such a name."""
    own = params.get(node_id, {})
    typo = difflib.get_close_matches(key, list(own), n=1, cutoff=TYPO)
    if typo:
        return (typo[0],)
    wanted = _words(key.replace("_", " "))
    ranked = []
    for node, docs in params.items():
        for name, doc in docs.items():
            in_name = wanted & _words(name.replace("_", " "))
            covered = in_name | (wanted & _words(doc))
            if covered:
                ratio = difflib.SequenceMatcher(None, key, name).ratio()
                ranked.append(((len(covered), len(in_name), node == node_id, ratio), node, name))
    if ranked:
        ranked.sort(key=lambda item: item[0], reverse=True)
        chosen = [(node, name) for score, node, name in ranked[:SUGGESTED] if score[0] >= ranked[0][0][0] - 1]
        if all(node == node_id for node, _ in chosen):
            return tuple(name for _, name in chosen)
        return tuple(f"{node}.{name}" for node, name in chosen)  # another node's among them: each says its node
    near = nearest(key, own)
    return (near,) if near else ()


def _parse_override(text: str) -> tuple[list[str], Any]:
    if "=" not in text:
        raise ValueError("expected node.param=value")
    target, _, raw = text.partition("=")
    try:
        value = yaml.safe_load(raw) if raw.strip() else None
    except yaml.YAMLError:
        value = raw
    return target.strip().split("."), value


def _valid_fields(raw: dict) -> RecipeModel:
    """The top-level fields of ``raw`` that are valid on their own, the others at their defaults (outputs and
    nodes empty): what a recipe whose top level has an error still gets checked against."""
    model = RecipeModel.model_construct(outputs=[], nodes={})
    for name in RecipeModel.model_fields:
        if name in raw:
            try:
                RecipeModel.__pydantic_validator__.validate_assignment(model, name, raw[name])
            except ValidationError:
                pass
    return model


class _Validator:
    """Collects issues while building a Recipe."""

    def __init__(
        self,
        raw: dict,
        source: SourceMap,
        registry: Registry,
        overrides: list[str],
        name: str | None,
        draft=False,
        work=False,
        yes=False,
        limits: Limits | None = None,
    ):
        from .cost import Limits

        self.raw = raw
        self.work, self.yes = work, yes
        self.limits = limits or Limits()
        self.source = source
        self.registry = registry
        self.draft = draft
        self.overrides = overrides
        self.name = name
        recipe_file = Path(source.file)
        self.base_dir = recipe_file.resolve().parent if recipe_file.is_file() else None
        named = raw.get("name") if isinstance(raw, dict) else None  # a recipe that is not a mapping is refused later
        self.file_name = recipe_file_name(recipe_file, str(named or name or recipe_file.stem))
        self.issues: list[Issue] = []
        self.warnings: list[Issue] = []  # what a run's nodes will warn of, the recipe alone deciding (``warns_of``)
        self.override_at: dict[tuple, Location] = {}

    def _param_docs(self) -> dict[str, dict[str, str]]:
        """Every parameter of the recipe's nodes with its doc, by node (what ``nearest_params`` matches on)."""
        nodes = self.raw.get("nodes") if isinstance(self.raw.get("nodes"), dict) else {}
        docs = {}
        for node_id, entry in nodes.items():
            spec = self.registry.get(entry.get("type")) if isinstance(entry, dict) else None
            if spec is not None:
                docs[str(node_id)] = {name: param.doc or "" for name, param in spec.params.items()}
        return docs

    def issue(self, path: tuple, message: str, key: bool = False, **extra) -> None:
        location = self.override_at.get(tuple(path[:4])) or self.source.at(path, key=key)
        self.issues.append(Issue(location, message, **extra))

    def pydantic_issues(self, exc: ValidationError, base: tuple, node: str | None, model: type[BaseModel]) -> None:
        """pydantic errors as issues at their line; a value failing every member of a union is one issue."""
        by_path: dict[tuple, list[dict]] = {}
        for err in exc.errors():
            by_path.setdefault(self._data_path(base, err["loc"]), []).append(err)
        for loc, errors in by_path.items():
            err = errors[0]
            field_name = str(loc[-1]) if len(loc) > len(base) else None
            if err["type"] == "extra_forbidden":
                self.issue(
                    loc,
                    f"unknown key '{field_name}'",
                    key=True,
                    node=node,
                    allowed=", ".join(model.model_fields),
                    suggestion=nearest(field_name, model.model_fields),
                )
            elif err["type"] == "missing":
                self.issue(loc[:-1], f"missing required key '{field_name}'", node=node)
            else:
                given = err.get("input")
                tags = [str(e["loc"][-1]) for e in errors if e["loc"]]
                message = err["msg"] if len(errors) == 1 else "not a valid value"
                self.issue(
                    loc,
                    message,
                    node=node,
                    param=field_name,
                    given=given if not isinstance(given, (dict, list)) else None,
                    allowed=" or ".join(tags) if len(errors) > 1 else None,
                )

    def _data_path(self, base: tuple, loc: tuple) -> tuple:
        """The part of a pydantic location that addresses the recipe data (drops union-member tags)."""
        data = self.raw
        for key in base:
            data = data.get(key) if isinstance(data, dict) else None
        path = list(base)
        for part in loc:
            if isinstance(data, dict):  # a key: present, unknown or missing, it is where the problem is
                path.append(part)
                data = data.get(part)
            elif isinstance(data, list) and isinstance(part, int):
                path.append(part)
                data = data[part] if part < len(data) else None
            else:  # a scalar was reached: the rest of the location names union members
                break
        return tuple(path)

    def draft_overrides(self) -> list[tuple[str, Location]]:
        """The ``draft:`` block as ``node.param=value`` texts, each located at its line in the recipe."""
        block = self.raw.get("draft")
        if not isinstance(block, dict) or not block:
            self.issue(
                ("draft",) if "draft" in self.raw else (),
                "--draft: this recipe has no draft: block",
                allowed="a top-level mapping of reduced sizes, e.g. draft: {rice_place.r: 3.0, preview.width: 320}",
            )
            return []
        return [
            (f"{key}={json.dumps(value)}", self.source.at(("draft", key), key=True)) for key, value in block.items()
        ]

    def apply_overrides(self) -> None:
        nodes = self.raw.get("nodes") if isinstance(self.raw.get("nodes"), dict) else {}
        given = [(text, Location("--set", i)) for i, text in enumerate(self.overrides, 1)]
        drafted = self.draft_overrides() if self.draft else []
        self.overrides = [text for text, _ in drafted] + list(self.overrides)  # --set wins over the draft
        for text, where in drafted + given:
            try:
                target, value = _parse_override(text)
            except ValueError as exc:
                self.issues.append(Issue(where, f"cannot read '{text}': {exc}"))
                continue
            if target == ["seed"]:
                self.raw["seed"] = value
                self.override_at[("seed",)] = where
                continue
            if len(target) == 1 and (having := self._having(target[0], nodes)):
                self.issues.append(
                    Issue(
                        where,
                        f"'{target[0]}' names no node: a parameter is set on its node, as node.param=value",
                        given=text,
                        allowed="the nodes that have it: " + ", ".join(having),
                        suggestion=f"{having[0]}={text.partition('=')[2]}" if len(having) == 1 else None,
                    )
                )
                continue
            if len(target) != 2 or not all(target):
                self.issues.append(Issue(where, f"cannot read '{text}'", allowed="node.param=value or seed=N"))
                continue
            node_id, key = target
            if node_id not in nodes:
                near = self._nearest_having(node_id, key, nodes)
                self.issues.append(
                    Issue(
                        where,
                        f"no node '{node_id}' in the recipe",
                        given=text,
                        suggestion=f"{near}={text.partition('=')[2]}" if near else nearest(node_id, nodes),
                    )
                )
                continue
            entry = nodes[node_id]
            if not isinstance(entry, dict):
                continue
            if key in ("variants", "seed"):
                entry[key] = value
                self.override_at[("nodes", node_id, key)] = where
            else:
                params = entry.setdefault("params", {})
                if isinstance(params, dict):
                    params[key] = value
                    self.override_at[("nodes", node_id, "params", key)] = where

    def _having(self, param: str, nodes: dict) -> list[str]:
        """``node.param`` for each node of the raw recipe whose type declares ``param``: what a bare
        ``--set param=value`` may have meant."""
        types = {node_id: body.get("type") for node_id, body in nodes.items() if isinstance(body, dict)}
        specs = {node_id: self.registry.get(t) for node_id, t in types.items() if isinstance(t, str)}
        return [f"{node_id}.{param}" for node_id, spec in specs.items() if spec is not None and param in spec.params]

    def _nearest_having(self, node_id: str, param: str, nodes: dict) -> str | None:
        """The ``node.param`` an unknown ``node_id.param`` most likely meant: among the nodes whose type declares
        ``param``, the one whose name is closest to ``node_id`` (``nearest``; ``shift.dx``: ``shifted.dx``, not
        ``shifts``, which has no ``dx``); None where none is close."""
        having = {name.partition(".")[0]: name for name in self._having(param, nodes)}
        near = nearest(node_id, having)
        return having[near] if near else None

    def build(self) -> Recipe | None:
        if not isinstance(self.raw, dict):
            self.issue((), "a recipe must be a mapping with keys name, seed, effects, outputs, nodes")
            return None
        self.apply_overrides()
        try:
            model = partial = RecipeModel.model_validate(self.raw)
        except ValidationError as exc:
            self.pydantic_issues(exc, (), None, RecipeModel)
            model, partial = None, _valid_fields(self.raw)
        raw_nodes = self.raw.get("nodes") if isinstance(self.raw.get("nodes"), dict) else {}

        entries: dict[str, NodeEntry] = {}
        wire_sources: dict[tuple[str, str], list[tuple[Wire, tuple]]] = {}
        before_nodes = len(self.issues)
        above = None  # the node before this one in the file
        for node_id, body in raw_nodes.items():
            path = ("nodes", node_id)
            above, node_above = node_id, above
            if not isinstance(node_id, str) or not NODE_ID.match(node_id):
                self.issue(
                    path,
                    f"invalid node id '{node_id}'",
                    key=True,
                    allowed="letters, digits and _ (not starting with a digit)",
                )
                continue
            if node_id in NodeModel.model_fields and not (isinstance(body, dict) and "type" in body):
                # a node's key indented too little (a node of that name would have a type)
                under = f"node '{node_above}' above" if node_above else "its node"
                self.issue(
                    path,
                    f"'{node_id}' is a key of a node, not a node: check the indentation; indent it under "
                    f"{under}, 2 spaces further in than the node's name",
                    key=True,
                )
                continue
            if body is None:
                self.issue(
                    path,
                    "nothing under it: put its type (and params, inputs) on the lines below, "
                    f"2 spaces further in than '{node_id}:'",
                    key=True,
                    node=node_id,
                )
                continue
            if not isinstance(body, dict):
                hint = f" (for a node type, write '{node_id}: {{type: {body}}}')" if isinstance(body, str) else ""
                self.issue(
                    path,
                    f"a node must be a mapping (type, params, inputs, variants), not a {type(body).__name__}{hint}",
                    node=node_id,
                    given=body if not isinstance(body, list) else None,
                    allowed="a mapping with at least 'type'",
                )
                continue
            try:
                node_model = NodeModel.model_validate(body if body is not None else {})
            except ValidationError as exc:
                self.pydantic_issues(exc, path, node_id, NodeModel)
                continue
            entry = self._node(node_id, node_model, path, wire_sources)
            if entry is not None:
                entries[node_id] = entry

        graph = Dag(entries)
        self._check_wires(entries, wire_sources, graph, raw_nodes)
        cyclic = self._check_cycles(graph)
        if not cyclic:
            self._check_families(entries, graph)
        nodes_valid = len(self.issues) == before_nodes
        # the outputs and effects as written are checked whatever else is wrong (an unknown top-level key, a bad
        # --set): each error of a recipe is reported in one pass, not one per fix
        outputs = self._check_outputs(partial.outputs, entries, raw_nodes)
        effects = self._check_effects(partial.effects, entries)
        cost = None
        if nodes_valid:  # the nodes' checks across the recipe read valid parameters and wires only
            self._check_recipe_rules(entries)
            if self.work and not cyclic and not self.issues:
                cost = self._weigh_cost(entries, graph, outputs, effects)
        self._check_draft(entries)
        raw_sweeps = self.raw.get("sweeps")
        sweeps = {}
        if isinstance(raw_sweeps, dict):  # its models are built on import: only for a recipe that declares sweeps
            from .sweep_decl import check_sweeps

            sweeps = check_sweeps(self, raw_sweeps, entries, raw_nodes)
        if partial.name is not None and not PLAIN_NAME.match(partial.name):
            self.issue(
                ("name",),
                "the recipe name names its output folder and recording, so it must be a plain name",
                param="name",
                given=partial.name,
                allowed="letters, digits, _, - and . (not starting with '.'; no '/', '\\' or '..')",
            )
        if self.issues or model is None:
            return None
        name = model.name or self.name or Path(self.source.file).stem
        return Recipe(
            name=name,
            file_name=self.file_name,
            path=self.source.file,
            seed=model.seed,
            effects=effects,
            outputs=outputs,
            nodes=entries,
            source=self.source,
            graph=graph,
            overrides=tuple(self.overrides),
            sweeps=sweeps,
            draft=tuple(f"{key}={json.dumps(value)}" for key, value in model.draft.items()),
            cost=cost,
            warnings=tuple(self.warnings),
        )

    def _check_recipe_rules(self, entries: dict[str, NodeEntry]) -> None:
        """Each node type's ``check_recipe``: contradictions between the nodes of a valid recipe; with ``work``,
        each one's ``check_work`` too (with ``yes``, less what ``--yes`` passes), and what each will warn of
        (``warns_of``: a user's file it repairs), kept as warnings."""
        view = MappingProxyType(entries)
        for node_id, entry in entries.items():
            if entry.spec.check_recipe is None:
                continue
            for param, message in entry.spec.check_recipe(node_id, view):
                self.issue(("nodes", node_id, "params", param), message, node=node_id, param=param)
        for node_id, entry in entries.items() if self.work else ():
            for param, message, passes_with_yes in (
                entry.spec.check_work(node_id, view) if entry.spec.check_work else ()
            ):
                if passes_with_yes and self.yes:
                    continue
                message += "; or run with --yes to go ahead" if passes_with_yes else ""
                self.issue(("nodes", node_id, "params", param), message, node=node_id, param=param)
            for param, message in entry.spec.warns(node_id, view) if entry.spec.warns is not None else ():
                at = ("nodes", node_id, "params", param)
                self.warnings.append(Issue(self.override_at.get(at) or self.source.at(at), message, node_id, param))

    def _weigh_cost(self, entries: dict[str, NodeEntry], graph: Dag, outputs: list[Wire], effects: frozenset[str]):
        """The cost estimate of the recipe's outputs (or those the limits name) and what they need
        (``nodegraph.cost``); what is over a run's limits is an issue at the parameter to change (with ``yes``, less
        what ``--yes`` passes)."""
        from .cost import estimate

        asked = list(self.limits.outputs or [w.node for w in outputs])
        needed = set(asked).union(*(graph.ancestors(node_id) for node_id in asked))
        result = estimate(MappingProxyType(entries), graph.topological_order(needed), asked, self.limits, effects)
        for node_id, param, message, passes_with_yes in result.over():
            if passes_with_yes and self.yes:
                continue
            message += "; or run with --yes to go ahead" if passes_with_yes else ""
            at = ("nodes", node_id, "params", param) if param else ("nodes", node_id)  # a node with no lever: itself
            self.issue(at, message, node=node_id, param=param)
        return result

    def _moved(self, node_id: str, model: NodeModel, path: tuple, moved, key: str) -> None:
        """A parameter the node type no longer has: say where it lives now (the node wired into the input
        ``moved`` names, at its file:line, or how to wire one)."""
        wired = model.inputs.get(moved.input) or ""
        target = (wired[0] if isinstance(wired, list) else wired).partition(".")[0]
        nodes = self.raw.get("nodes") if isinstance(self.raw.get("nodes"), dict) else {}
        if target in nodes:
            where = self.source.at(("nodes", target, "params", moved.param))
            given = model.params[key]
            advice = f"that node is '{target}' at {where}: set '{moved.param}' there"
            advice += f", or --set {target}.{moved.param}={given}"
        else:
            advice = f"wire a {moved.node_type} node into input '{moved.input}' and set its '{moved.param}' there"
        self.issue(path, f"{moved.advice(key)}; {advice}", key=True, node=node_id)

    def _check_draft(self, entries: dict) -> None:
        """Every key of the draft: block names a node's parameter (or its variants or seed), or the seed."""
        block = self.raw.get("draft")
        raw_nodes = self.raw.get("nodes") if isinstance(self.raw.get("nodes"), dict) else {}
        for key in block if isinstance(block, dict) and not self.draft else ():  # --draft reports as it applies
            node_id, _, param = str(key).partition(".")
            if key == "seed" or node_id in raw_nodes and node_id not in entries:  # a broken node is reported
                continue
            if node_id not in entries:
                self.issue(
                    ("draft", key),
                    f"draft: no node '{node_id}' in the recipe",
                    key=True,
                    suggestion=nearest(node_id, entries),
                )
            elif param not in (*entries[node_id].spec.params, "variants", "seed"):
                self.issue(
                    ("draft", key),
                    f"draft: node '{node_id}' has no parameter '{param}'",
                    key=True,
                    node=node_id,
                    allowed=", ".join(entries[node_id].spec.params),
                    suggestion=nearest(param, entries[node_id].spec.params),
                )

    def _node(self, node_id: str, model: NodeModel, path: tuple, wire_sources) -> NodeEntry | None:
        spec = self.registry.get(model.type)
        if spec is None:
            self.issue(
                path + ("type",),
                f"unknown node type '{model.type}'",
                node=node_id,
                suggestion=nearest(model.type, self.registry.names()),
                allowed="see `nodegraph nodes`",
            )
            return None
        params: dict[str, Any] = {}
        ok = True
        for key, value in model.params.items():
            param = spec.params.get(key)
            if param is None and key in spec.moved:
                self._moved(node_id, model, path + ("params", key), spec.moved[key], key)
                ok = False
                continue
            if param is None:
                self.issue(
                    path + ("params", key),
                    f"unknown parameter '{key}' for {spec.type_name}",
                    key=True,
                    node=node_id,
                    allowed=", ".join(spec.params) or "(none)",
                    suggestion=_one_or_more(nearest_params(node_id, key, self._param_docs())),
                )
                ok = False
                continue
            from_file = ("nodes", node_id, "params", key) not in self.override_at
            try:
                # a relative file path written in the recipe is taken from the recipe's folder (the recipe
                # runs from anywhere); one given with --set from the working directory, as a shell would
                params[key] = param.validate(value, base=self.base_dir if from_file else None)
            except ParamValueError as exc:
                self.issue(path + ("params", key), str(exc), node=node_id, param=key, given=value, allowed=exc.allowed)
                ok = False
        for key, param in spec.params.items():
            if key not in params:
                if param.required:
                    if key not in model.params:
                        self.issue(
                            path,
                            f"missing required parameter '{key}'",
                            key=True,
                            node=node_id,
                            param=key,
                            allowed=param.allowed(),
                        )
                    ok = False
                else:
                    params[key] = self.file_name if param.default is RECIPE_FILE_NAME else param.default
        if ok and spec.check is not None:
            for param_name, message in spec.check(dict(params)):
                self.issue(
                    path + ("params", param_name), message, node=node_id, param=param_name, given=params.get(param_name)
                )
                ok = False

        inputs: dict[str, list[Wire]] = {}
        for port_name, refs in model.inputs.items():
            port = spec.inputs.get(port_name)
            port_path = path + ("inputs", port_name)
            if port is None:
                self.issue(
                    port_path,
                    f"unknown input port '{port_name}' for {spec.type_name}",
                    key=True,
                    node=node_id,
                    allowed=", ".join(spec.inputs) or "(none)",
                    suggestion=nearest(port_name, spec.inputs),
                )
                continue
            ref_list = refs if isinstance(refs, list) else [refs]
            if isinstance(refs, list) and not port.many:
                self.issue(
                    port_path,
                    f"input '{port_name}' takes one wire, got a list of {len(refs)}",
                    node=node_id,
                    allowed="node.port",
                )
                continue
            wires = []
            for i, ref in enumerate(ref_list):
                ref_path = port_path + ((i,) if isinstance(refs, list) else ())
                node_ref, _, port_ref = ref.partition(".")
                wire = Wire(node_ref, port_ref)
                wires.append(wire)
                wire_sources.setdefault((node_id, port_name), []).append((wire, ref_path))
            inputs[port_name] = wires
        for port_name, port in spec.inputs.items():
            if port_name not in inputs and not port.optional and port_name not in model.inputs:
                self.issue(
                    path,
                    f"missing required input '{port_name}' ({port.type_name})",
                    key=True,
                    node=node_id,
                    param=f"inputs.{port_name}",
                )
        return NodeEntry(node_id, spec, params, inputs, model.variants, model.seed)

    def _resolve_port(self, wire: Wire, entries) -> str | None:
        """The output port a wire names; ``node`` alone is allowed when that node has one output."""
        source = entries[wire.node].spec
        if wire.port:
            return wire.port if wire.port in source.outputs else None
        return next(iter(source.outputs)) if len(source.outputs) == 1 else None

    def _check_wires(self, entries, wire_sources, graph, raw_nodes) -> None:
        for (node_id, port_name), wires in wire_sources.items():
            if node_id not in entries:
                continue
            entry = entries[node_id]
            port = entry.spec.inputs[port_name]
            resolved = []
            for wire, path in wires:
                if wire.node not in entries:
                    if wire.node in raw_nodes:
                        continue  # that node has its own issue already
                    self.issue(
                        path,
                        f"input '{port_name}' refers to unknown node '{wire.node}'",
                        node=node_id,
                        given=str(wire) if wire.port else wire.node,
                        suggestion=nearest(wire.node, raw_nodes),
                    )
                    continue
                source_spec = entries[wire.node].spec
                port_ref = self._resolve_port(wire, entries)
                if port_ref is None:
                    what = (
                        f"'{wire.node}' has no output '{wire.port}'"
                        if wire.port
                        else f"'{wire.node}' has several outputs; name one as {wire.node}.<port>"
                    )
                    self.issue(
                        path,
                        what,
                        node=node_id,
                        param=f"inputs.{port_name}",
                        allowed=", ".join(f"{wire.node}.{p}" for p in source_spec.outputs),
                        suggestion=nearest(wire.port, source_spec.outputs) if wire.port else None,
                    )
                    continue
                out = source_spec.outputs[port_ref]
                if not issubclass(out.type, port.type):
                    self.issue(
                        path,
                        f"type mismatch: {wire.node}.{port_ref} gives {out.type_name}, "
                        f"input '{port_name}' of {entry.spec.type_name} takes {port.type_name}",
                        node=node_id,
                        param=f"inputs.{port_name}",
                    )
                    continue
                resolved.append(Wire(wire.node, port_ref))
                graph.add_edge(wire.node, node_id)
            entry.inputs[port_name] = resolved

    def _check_cycles(self, graph: Dag) -> bool:
        ids = graph.find_cycle()
        if ids is None:
            return False
        self.issue(("nodes", ids[0]), "cycle: " + " → ".join(ids), key=True, node=ids[0])
        return True

    def _check_families(self, entries: dict[str, NodeEntry], graph: Dag) -> None:
        """Variant families: a plain port fed by a family maps the node over it; a many-port gathers it."""
        for node_id in graph.topological_order():
            entry = entries[node_id]
            sizes: dict[int, str] = {}
            for port_name, wires in entry.inputs.items():
                if entry.spec.inputs[port_name].many:
                    continue
                for wire in wires:
                    size = entries[wire.node].family
                    if size is not None:
                        sizes.setdefault(size, wire.node)
            if entry.variants is not None:
                sizes.setdefault(entry.variants, "its own 'variants'")
            if len(sizes) > 1:
                detail = ", ".join(f"{n} from {src}" for n, src in sorted(sizes.items()))
                self.issue(
                    ("nodes", node_id),
                    f"inputs come in variant families of different sizes ({detail})",
                    key=True,
                    node=node_id,
                )
            entry.family = min(sizes) if sizes else None

    def _check_outputs(self, outputs: list[str], entries, raw_nodes) -> list[Wire]:
        """``node.port``, or ``node`` for all of a node's outputs."""
        wires = []
        for i, ref in enumerate(outputs):
            node_ref, _, port_ref = ref.partition(".")
            path = ("outputs", i)
            if node_ref not in entries:
                if node_ref not in raw_nodes:
                    self.issue(
                        path,
                        f"output refers to unknown node '{node_ref}'",
                        given=ref,
                        suggestion=nearest(node_ref, raw_nodes),
                    )
                continue
            spec = entries[node_ref].spec
            if not port_ref:
                wires += [Wire(node_ref, port) for port in spec.outputs]
            elif port_ref in spec.outputs:
                wires.append(Wire(node_ref, port_ref))
            else:
                self.issue(
                    path,
                    f"'{node_ref}' has no output '{port_ref}'",
                    given=ref,
                    allowed=", ".join(f"{node_ref}.{p}" for p in spec.outputs),
                    suggestion=nearest(port_ref, spec.outputs),
                )
        return wires

    def _check_effects(self, effects: list[str], entries) -> frozenset[str]:
        known = self.registry.effects()
        in_recipe = {e for entry in entries.values() for e in entry.spec.effects}
        for i, effect in enumerate(effects):
            path = ("effects", i)
            if effect not in known:
                self.issue(
                    path,
                    f"unknown effect '{effect}'",
                    given=effect,
                    allowed=", ".join(sorted(known)) or "(no node implements any effect)",
                    suggestion=nearest(effect, known),
                )
            elif effect not in in_recipe:
                implementers = sorted(s.type_name for s in self.registry.specs() if effect in s.effects)
                self.issue(
                    path,
                    f"effect '{effect}' is asked for but no node in this recipe implements it",
                    given=effect,
                    allowed="add a node of type " + " or ".join(implementers),
                )
        return frozenset(effects)


def parse_recipe(text: str, registry: Registry, file: str = "<recipe>", overrides: list[str] = ()) -> Recipe:
    """Validate recipe text; raise RecipeError listing every problem."""
    raw, source = load_yaml(text, file)
    return _finish(raw, source, registry, list(overrides), None)


def load_recipe(
    path: str | Path,
    registry: Registry,
    overrides: list[str] = (),
    draft: bool = False,
    work: bool = False,
    yes: bool = False,
    limits: Limits | None = None,
) -> Recipe:
    """Load and validate a recipe file; raise RecipeError listing every problem with file:line:column.

    ``draft``: apply the recipe's ``draft:`` block (reduced counts to iterate on a look) before ``overrides``;
    the recipe's ``overrides`` then start with the draft's, so a worker that reloads it gets the same recipe.
    ``work``: the nodes' ``check_work`` too, what takes a moment to check (``nodegraph check``; ``run`` when there
    is work to do), and the recipe's cost estimate (``Recipe.cost``) against ``limits``; ``yes``: less the requests
    larger than a run starts on unasked (``--yes``)."""
    raw, source = load_yaml_file(path)
    return _finish(raw, source, registry, list(overrides), Path(path).stem, draft, work, yes, limits)


def _finish(raw, source, registry, overrides, name, draft=False, work=False, yes=False, limits=None) -> Recipe:
    validator = _Validator(raw, source, registry, overrides, name, draft, work, yes, limits)
    recipe = validator.build()
    if validator.issues or recipe is None:
        issues = sorted(
            validator.issues,
            key=lambda i: (
                i.location.file != source.file,
                i.location.file,
                i.location.line or 0,
                i.location.column or 0,
            ),
        )
        raise RecipeError(issues or [Issue(source.at(()), "invalid recipe")])
    return recipe
