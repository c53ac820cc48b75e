"""``nodegraph describe``: a node type's ports and parameters, found by a type's name, a step's name in a recipe or
a name's start; a step's values in its recipe (and its draft) beside each default."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from .errors import NodegraphError
from .yaml_source import nearest_recipe


def describe_spec(spec, values: StepValues | None = None) -> str:
    """Plain-text description of a node type: header, doc, ports, parameters (readable in a pipe); with ``values``,
    what a recipe's step sets beside each default."""
    lines = [f"{spec.type_name}  ({spec.module})"]
    if spec.doc:
        lines += ["", *spec.doc.splitlines()]
    lines += ["", f"random: {'yes (seeded per node and variant)' if spec.random else 'no'}"]
    if spec.effects:
        lines.append(f"effects: {', '.join(sorted(spec.effects))}")
    if not spec.store:
        lines.append("cached: no (cheaper to compute again than to store)")
    for title, ports in (("inputs", spec.inputs), ("outputs", spec.outputs)):
        lines += ["", f"{title}:"] + ([] if ports else ["  (none)"])
        for name, port in ports.items():
            flags = " (optional)" if getattr(port, "optional", False) else ""
            lines.append(f"  {name:<16} {port.type_name + flags:<24} {port.doc}")
            if getattr(port, "columns", ()):
                lines.append(f"  {'':<16} {'':<24} columns: {', '.join(port.columns)}")
    lines += ["", "parameters:"] + ([] if spec.params else ["  (none)"])
    for name, param in spec.params.items():
        d = param.describe()
        lines.append(f"  {name:<16} {d['type']:<24} {_param_facts(d, name, values, units=True)}")
        if d["doc"]:
            lines.append(f"  {'':<16} {d['doc']}")
    return "\n".join(lines)


def _param_facts(d: dict[str, str], name: str, values: StepValues | None, units: bool = False) -> str:
    """A parameter's default, the values a recipe's step gives it (``recipe``, ``--draft``), range and units."""
    given = values.of(name) if values is not None else ()
    return "  ".join(
        x
        for x in (
            f"default {d['default']}",
            *given,
            d["range"] and f"range {d['range']}",
            d["units"] and (f"units {d['units']}" if units else d["units"]),
        )
        if x
    )


@dataclasses.dataclass
class StepValues:
    """What one step of a recipe sets (read as plain YAML, nothing validated): its ``params:`` and its recipe's
    ``draft:`` entries for it, shown by ``describe`` beside the type's defaults."""

    recipe: str
    type_name: str
    params: dict
    draft: dict

    def of(self, name: str) -> tuple[str, ...]:
        """``recipe VALUE`` and ``--draft VALUE`` for the parameter ``name``, where the recipe sets them."""
        sets = (("recipe", self.params), ("--draft", self.draft))
        return tuple(f"{label} {given[name]!r}" for label, given in sets if name in given)


def step_values(recipe: str | Path, step: str) -> StepValues | None:
    """The values the step ``step`` of the recipe file ``recipe`` sets; None where it has no such step."""
    import yaml

    try:
        raw = yaml.safe_load(Path(recipe).read_text())
    except (OSError, yaml.YAMLError):
        return None
    body = _recipe_nodes(raw).get(step)
    if not isinstance(body, dict) or not isinstance(body.get("type"), str):
        return None
    params = body.get("params") if isinstance(body.get("params"), dict) else {}
    draft = raw.get("draft") if isinstance(raw.get("draft"), dict) else {}
    drafted = {str(key).partition(".")[2]: v for key, v in draft.items() if str(key).partition(".")[0] == step}
    return StepValues(str(recipe), body["type"], params, drafted)


def _recipe_nodes(raw) -> dict:
    """A recipe's ``nodes:`` mapping as plain YAML read it (empty where it has none)."""
    nodes = raw.get("nodes") if isinstance(raw, dict) else None
    return nodes if isinstance(nodes, dict) else {}


def recipe_steps(name: str, folders=(Path("."), Path("graphs"))) -> dict[str, list[str]]:
    """{node type: [recipe files]} of the steps called ``name`` in the recipes of ``folders`` (read as plain YAML,
    nothing validated): ``describe`` takes a step's name as a user reads it in a recipe."""
    import yaml

    found: dict[str, list[str]] = {}
    for path in sorted({p for folder in folders for p in folder.glob("*.yaml")}):
        try:
            step = yaml.safe_load(path.read_text()).get("nodes", {}).get(name)
        except (OSError, yaml.YAMLError, AttributeError):
            continue
        if isinstance(step, dict) and isinstance(step.get("type"), str):
            found.setdefault(step["type"], []).append(str(path))
    return found


def describe_command(first: str, second: str | None, registry) -> str:
    """What ``nodegraph describe [RECIPE.yaml] TYPE_OR_STEP[.SETTING]`` prints: a node type, found by its name, a
    step's name (in the recipe given, else in the recipes here and in graphs/) or its name's start; a step's values
    beside the defaults."""
    recipe = Path(first) if second is not None else None  # describe RECIPE STEP: the step as that recipe sets it
    if recipe is not None and not recipe.is_file():
        near = nearest_recipe(recipe)
        hint = f"; did you mean {near}?" if near else ""
        raise NodegraphError(f"{recipe}: no such recipe{hint} (describe RECIPE.yaml STEP, or describe STEP)")
    given = second if second is not None else first
    name, _, setting = given.partition(".")  # README's `step.setting` names a step's parameter
    spec = registry.get(name)
    if spec is not None and recipe is None:
        return _setting_line(spec, setting) + describe_spec(spec) + "\n"
    import difflib

    if recipe is not None:
        values = step_values(recipe, name)
        if values is None:
            import yaml

            try:
                steps = list(_recipe_nodes(yaml.safe_load(recipe.read_text())))
            except yaml.YAMLError:
                steps = []
            near = difflib.get_close_matches(name, steps, n=3)
            hint = f"; did you mean {' or '.join(repr(n) for n in near)}?" if near else ""
            raise NodegraphError(f"no step '{name}' in {recipe}{hint} (its steps: {', '.join(steps)})")
        return f"'{name}' is a step of {recipe}: node type {values.type_name}\n\n" + _describe_type(
            registry, values.type_name, setting, values
        )
    steps = {t: files for t, files in recipe_steps(name).items() if registry.get(t) is not None}
    prefixed = [n for n in registry.names() if n.startswith(name)]
    values = None
    if len(steps) == 1:
        ((type_name, files),) = steps.items()
        values = step_values(files[0], name)
        more = (
            f" and {len(files) - 1} more recipes (the values shown are {files[0]}'s; another's: "
            f"nodegraph describe RECIPE.yaml {given})"
            if len(files) > 1
            else ""
        )
        head = f"'{name}' is a step of {files[0]}{more}: node type {type_name}\n\n"
    elif not steps and len(prefixed) == 1:
        type_name = prefixed[0]
        head = f"'{name}' begins node type {type_name}\n\n"
    else:
        near = ([*steps] or prefixed)[:5] or difflib.get_close_matches(name, registry.names(), n=3)
        hint = (
            f"; did you mean {' or '.join(repr(n) for n in near)}?"
            if near
            else "; a step of a recipe is found by its name in the recipes here and in graphs/"
        )
        raise NodegraphError(f"unknown node type '{name}'{hint} (see `nodegraph nodes`)")
    return head + _describe_type(registry, type_name, setting, values)


def _describe_type(registry, type_name: str, setting: str, values: StepValues | None) -> str:
    """Node type ``type_name`` (its setting ``setting`` first, if one is named) with a step's ``values``."""
    spec = registry.get(type_name)
    if spec is None:
        raise NodegraphError(f"unknown node type '{type_name}' (see `nodegraph nodes`)")
    return _setting_line(spec, setting, values) + describe_spec(spec, values) + "\n"


def _setting_line(spec, setting: str, values: StepValues | None = None) -> str:
    """The line that answers ``describe step.setting``: the setting's type, default, the recipe's value, range and
    doc (empty without one); an unknown setting is refused with the type's own."""
    if not setting:
        return ""
    param = spec.params.get(setting)
    if param is None:
        import difflib

        near = difflib.get_close_matches(setting, list(spec.params), n=3)
        hint = f"; did you mean {' or '.join(repr(n) for n in near)}?" if near else ""
        raise NodegraphError(
            f"{spec.type_name} has no setting '{setting}'{hint} (its settings: {', '.join(spec.params)})"
        )
    d = param.describe()
    return f"{setting}: {d['type']}  {_param_facts(d, setting, values)}\n  {d['doc']}\n\n"
