"""Parameter declarations: type, default, range, choices, units and a one-line doc, checked as data.

Type coercion uses pydantic's ``TypeAdapter`` (so ``tuple[float, float]`` or ``list[str]`` work as
annotations); ranges, choices and the wording of errors are ours, because a user needs the allowed
range and units in the message, not a pydantic error code.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, get_args, get_origin

from pydantic import TypeAdapter, ValidationError

REQUIRED: Any = type("Required", (), {"__repr__": lambda self: "REQUIRED"})()


class _RecipeFileName(str):
    """The default of a name that follows the recipe's file (``RECIPE_FILE_NAME``)."""

    def __repr__(self) -> str:
        return "the recipe's file name"


# a str parameter's default that a recipe fills with its file's name (``output_folder.recipe_file_name``), so a
# copy of a recipe names its files after itself; outside a recipe (``NodeSpec.call``) it reads "recipe"
RECIPE_FILE_NAME: Any = _RecipeFileName("recipe")


# the meshes the recipes in graphs/ name (``assets/bunny.ply``), where a copy of a recipe elsewhere no longer finds them
SHIPPED_ASSETS = Path(__file__).resolve().parent.parent / "graphs" / "assets"


def _missing_file(given: Path, base: Path | None) -> str:
    """What a file parameter whose file is missing accepts: where its relative path was taken from (the recipe's
    folder, or for ``--set`` the working folder) and, for a recipe, where the shipped assets are."""
    if given.is_absolute():
        return "an existing file"
    if base is None:
        return f"an existing file; a relative path given with --set is taken from where nodegraph runs, {Path.cwd()}"
    text = f"an existing file; a relative path in a recipe is taken from the recipe's folder, {base}"
    shipped = SHIPPED_ASSETS / given.name
    if shipped.is_file():
        return text + f"; the shipped one is {shipped}: write that path, or copy {SHIPPED_ASSETS} beside the recipe"
    if SHIPPED_ASSETS.is_dir():
        return text + f"; the shipped assets are in {SHIPPED_ASSETS}"
    return text


class ParamValueError(ValueError):
    """A parameter value is not allowed; ``allowed`` says what is."""

    def __init__(self, message: str, allowed: str):
        super().__init__(message)
        self.allowed = allowed


def _type_name(annotation: Any) -> str:
    origin = get_origin(annotation)
    if origin is None:
        return getattr(annotation, "__name__", str(annotation))
    args = ", ".join("..." if a is Ellipsis else _type_name(a) for a in get_args(annotation))
    name = getattr(origin, "__name__", str(origin))
    if name == "UnionType" or name == "Union":
        return " | ".join(_type_name(a) for a in get_args(annotation))
    return f"{name}[{args}]"


def _numbers_in(value: Any) -> list[float]:
    if isinstance(value, bool):
        return []
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, (list, tuple)):
        return [x for v in value for x in _numbers_in(v)]
    return []


def _has_bool_for_number(annotation: Any, value: Any) -> bool:
    """pydantic's lax mode turns True into 1; a boolean given for a number is a user mistake."""
    if annotation in (int, float):
        return isinstance(value, bool)
    args = get_args(annotation)
    if isinstance(value, (list, tuple)) and args:
        inner = [a for a in args if a is not Ellipsis]
        if len(inner) == 1:
            return any(_has_bool_for_number(inner[0], v) for v in value)
        return any(_has_bool_for_number(a, v) for a, v in zip(inner, value))
    return False


@dataclass(frozen=True)
class Param:
    """One declared node parameter.

    ``range`` is inclusive ``(low, high)`` (either may be None) and applies to every number in the
    value, so ``tuple[float, float]`` ranges or RGB colours are checked element-wise. ``file``: the
    value names an input file; it must exist, and its bytes enter the node's cache key (an edited
    file under the same name is read again).
    """

    type: Any
    default: Any = REQUIRED
    doc: str = ""
    range: tuple[float | None, float | None] | None = None
    choices: tuple[Any, ...] | None = None
    units: str = ""
    nullable: bool = False
    file: bool = False

    @cached_property
    def _adapter(self) -> TypeAdapter:
        return TypeAdapter(self.type)

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    @property
    def type_name(self) -> str:
        name = _type_name(self.type)
        return f"{name} | None" if self.nullable else name

    def allowed(self) -> str:
        """Human-readable description of the allowed values."""
        parts = [self.type_name]
        if self.choices is not None:
            parts = ["one of " + ", ".join(repr(c) for c in self.choices)]
        if self.range is not None:
            lo, hi = self.range
            if lo is not None and hi is not None:
                parts.append(f"{lo} ≤ value ≤ {hi}")
            elif lo is not None:
                parts.append(f"value ≥ {lo}")
            elif hi is not None:
                parts.append(f"value ≤ {hi}")
        if self.units:
            parts.append(f"in {self.units}")
        return ", ".join(parts)

    def validate(self, value: Any, base: Path | None = None) -> Any:
        """Coerce and check ``value``; raise ParamValueError saying what is allowed. A relative path of a
        ``file`` parameter is taken from ``base`` (the recipe's folder) when given, else the working folder."""
        if value is None:
            if self.nullable:
                return None
            raise ParamValueError("value must not be empty", self.allowed())
        if _has_bool_for_number(self.type, value):
            raise ParamValueError(f"expected {self.type_name}, got a boolean", self.allowed())
        try:
            coerced = self._adapter.validate_python(value)
        except ValidationError as exc:
            first = exc.errors()[0]
            raise ParamValueError(f"expected {self.type_name}: {first['msg'].lower()}", self.allowed()) from None
        if self.choices is not None and coerced not in self.choices:
            raise ParamValueError("not one of the allowed values", self.allowed())
        for number in _numbers_in(coerced):
            if math.isnan(number):
                raise ParamValueError("NaN is not a valid value", self.allowed())
            if self.range is not None:
                lo, hi = self.range
                if (lo is not None and number < lo) or (hi is not None and number > hi):
                    raise ParamValueError("out of range", self.allowed())
        if self.file:
            path = Path(coerced).expanduser()
            if base is not None and not path.is_absolute():
                path = base / path
                coerced = str(path)
            if path.is_dir():
                raise ParamValueError(f"{path} is a folder, not a file", self._file_in(path))
            if not path.is_file():
                raise ParamValueError(f"no such file: {path}", _missing_file(Path(value), base))
        return coerced

    def file_types(self) -> tuple[str, ...]:
        """The file name endings the parameter's doc names (".stl, .obj, .ply"), in its order."""
        return tuple(dict.fromkeys(re.findall(r"(?<![\w.])\.[A-Za-z][A-Za-z0-9]{0,5}\b", self.doc)))

    def _file_in(self, folder: Path) -> str:
        """What a file parameter given a folder accepts: a file of the types its doc names, and those in the
        folder."""
        types = self.file_types()
        found = sorted(p.name for p in folder.iterdir() if p.is_file() and (not types or p.suffix.lower() in types))
        accepted = f"a file of type {', '.join(types)}" if types else "a file"
        return accepted + (f"; in that folder: {', '.join(found[:5])}" if found else "")

    def describe(self) -> dict[str, str]:
        """The declaration as strings, for ``nodegraph describe`` and generated docs."""
        rng = ""
        if self.range is not None:
            lo, hi = self.range
            rng = f"[{'-∞' if lo is None else lo}, {'∞' if hi is None else hi}]"
        if self.choices is not None:
            rng = "{" + ", ".join(str(c) for c in self.choices) + "}"
        if self.file:
            rng = "an existing file (its content is in the cache key)"
        return {
            "type": self.type_name,
            "default": "(required)" if self.required else repr(self.default),
            "range": rng,
            "units": self.units,
            "doc": self.doc,
        }


def resolve(params: Mapping[str, Param], given: Mapping[str, Any]) -> dict[str, Any]:
    """Validated parameters with defaults filled in, a value per declared parameter; names not declared are
    ignored (raises ParamValueError / KeyError for a required parameter not given)."""
    values = {}
    for name, param in params.items():
        if name in given:
            values[name] = param.validate(given[name])
        elif param.required:
            raise KeyError(name)
        else:
            values[name] = param.default
    return values


def canonical(value: Any) -> Any:
    """A JSON-able canonical form of a validated parameter value (tuples become lists)."""
    if isinstance(value, (list, tuple)):
        return [canonical(v) for v in value]
    if isinstance(value, dict):
        return {str(k): canonical(v) for k, v in sorted(value.items())}
    if isinstance(value, float):
        # repr round-trips exactly; 1 and 1.0 have already been coerced to one type.
        return {"float": repr(value)}
    if isinstance(value, (int, str, bool)) or value is None:
        return value
    return {"repr": repr(value)}
