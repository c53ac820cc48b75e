"""Load YAML into plain Python values while remembering where every key and value came from.

PyYAML's composer already knows each node's start mark; we walk its node tree ourselves so that a
duplicate key is an error (PyYAML silently keeps the last) and every path gets a (line, column).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .errors import Issue, Location, RecipeError

PathKey = tuple[Any, ...]


@dataclass
class SourceMap:
    """(line, column) of each value and each mapping key, by path from the document root."""

    file: str
    values: dict[PathKey, tuple[int, int]] = field(default_factory=dict)
    keys: dict[PathKey, tuple[int, int]] = field(default_factory=dict)

    def at(self, path: PathKey, key: bool = False) -> Location:
        """Location of ``path``; falls back to the nearest enclosing path that has one."""
        table = self.keys if key else self.values
        probe = tuple(path)
        while probe:
            if probe in table:
                return Location(self.file, *table[probe])
            if probe in self.values:
                return Location(self.file, *self.values[probe])
            probe = probe[:-1]
        return Location(self.file, *self.values.get((), (1, 1)))


def _mark(node: yaml.Node) -> tuple[int, int]:
    return node.start_mark.line + 1, node.start_mark.column + 1


MAX_VALUES = 100_000  # a recipe is a few hundred values; YAML aliases can expand a short file without bound


class _TooLarge(Exception):
    """The document expands (through aliases) to more values than any recipe needs."""

    def __init__(self, node: yaml.Node):
        self.node = node


def _convert(
    node: yaml.Node,
    path: PathKey,
    source: SourceMap,
    issues: list[Issue],
    budget: list[int],
    open_nodes: frozenset[int] = frozenset(),
) -> Any:
    """Plain values from YAML nodes, at most ``budget[0]`` of them (aliases are expanded here, so a
    "billion laughs" document stops at the budget), a node inside itself refused."""
    budget[0] -= 1
    if budget[0] < 0 or id(node) in open_nodes:
        raise _TooLarge(node)
    source.values[path] = _mark(node)
    if isinstance(node, (yaml.MappingNode, yaml.SequenceNode)):
        open_nodes = open_nodes | {id(node)}
    if isinstance(node, yaml.MappingNode):
        result: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            key = _convert(key_node, path + ("<key>",), source, issues, budget, open_nodes)
            if not isinstance(key, (str, int, float, bool)) and key is not None:
                issues.append(Issue(Location(source.file, *_mark(key_node)), "a mapping key must be a scalar"))
                continue
            if key in result:
                first = source.keys[path + (key,)]
                issues.append(
                    Issue(
                        Location(source.file, *_mark(key_node)),
                        f"duplicate key '{key}' (first defined at line {first[0]})",
                    )
                )
                continue
            source.keys[path + (key,)] = _mark(key_node)
            result[key] = _convert(value_node, path + (key,), source, issues, budget, open_nodes)
        source.values.pop(path + ("<key>",), None)
        return result
    if isinstance(node, yaml.SequenceNode):
        return [_convert(item, path + (i,), source, issues, budget, open_nodes) for i, item in enumerate(node.value)]
    return yaml.SafeLoader.construct_object(_SCALAR_LOADER, node, deep=True)


class _ScalarLoader(yaml.SafeLoader):
    def __init__(self):
        super().__init__("")


_SCALAR_LOADER = _ScalarLoader()


INDENTATION_PROBLEMS = (
    "expected <block end>",
    "mapping values are not allowed here",
    "did not find expected key",
    "found character '\\t'",
    "found a tab character",
)


def indentation_hint(text: str, problem: str, mark) -> str:
    """What a parser's words about block structure usually mean in a recipe: a key indented too much or too
    little, or a tab. Names the line and the column its neighbours start at."""
    if not mark or not any(p in problem for p in INDENTATION_PROBLEMS):
        return ""
    lines = text.splitlines()
    row = min(mark.line, len(lines) - 1)
    if "\t" in lines[row][: len(lines[row]) - len(lines[row].lstrip())]:
        return f"; line {row + 1} is indented with a tab: indent with spaces only"
    indent = len(lines[row]) - len(lines[row].lstrip(" "))
    above = next(
        (
            len(line) - len(line.lstrip(" "))
            for line in reversed(lines[:row])
            if line.strip() and not line.lstrip().startswith("#")
        ),
        None,
    )
    context = f" (the line above starts at column {above + 1})" if above is not None else ""
    return (
        f"; check the indentation of line {row + 1}: it starts at column {indent + 1}{context}, and keys of "
        "one mapping must start in the same column (a value under a key: 2 spaces further in)"
    )


FLOW_OPENERS = {"while parsing a flow mapping": ("{", "}"), "while parsing a flow sequence": ("[", "]")}
QUOTED = "while scanning a quoted scalar"
# what the parser calls what it found, in words
TOKEN_WORDS = {
    "'?'": "a new key",
    "':'": "a ':'",
    "'-'": "a '-' list item",
    "'<stream end>'": "the end of the file",
    "'<block end>'": "the end of an indented block",
    "'<block mapping start>'": "an indented block",
}


def _closes_on_its_line(line: str, column: int, opener: str, closer: str) -> bool:
    """Whether the bracket at ``column`` of ``line`` is matched later on that line (quotes and comments aside)."""
    depth, quote = 0, None
    for char in line[column:]:
        if quote:
            quote = None if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char == "#":
            return False
        elif char == opener:
            depth += 1
        elif char == closer:
            depth -= 1
            if depth == 0:
                return True
    return False


def plain_syntax_error(text: str, exc: yaml.MarkedYAMLError, file: str) -> Issue:
    """A parser's complaint in a recipe writer's words, at the place to fix: an unclosed ``{`` or ``[`` where it
    was opened (the parser notices only lines later, at a token it names "'?'"), an unclosed quote where it
    starts; else the parser's own message, its token names put in words, with an indentation hint."""
    problem = exc.problem or str(exc)
    opened = FLOW_OPENERS.get(exc.context or "")
    start, mark = exc.context_mark, exc.problem_mark or exc.context_mark
    lines = text.splitlines()
    if opened and start is not None and mark is not None and problem.startswith("expected ','"):
        opener, closer = opened
        kind = "mapping" if opener == "{" else "list"
        line = lines[start.line] if start.line < len(lines) else ""
        if mark.line > start.line and not _closes_on_its_line(line, start.column, opener, closer):
            return Issue(
                Location(file, start.line + 1, start.column + 1),
                f"YAML syntax error: the `{opener}` opened on line {start.line + 1} is never closed: add the "
                f"`{closer}` that ends its {kind}",
            )
        return Issue(
            Location(file, mark.line + 1, mark.column + 1),
            f"YAML syntax error: inside the `{opener}…{closer}` {kind} opened on line {start.line + 1}, a `,` "
            f"between entries or the closing `{closer}` is needed here",
        )
    if exc.context == QUOTED and start is not None:
        return Issue(
            Location(file, start.line + 1, start.column + 1),
            f"YAML syntax error: the quote opened on line {start.line + 1} is never closed: end the text with the "
            "same quote mark",
        )
    problem = problem.replace("expected <block end>", "expected the indented block to end")
    for token, words in TOKEN_WORDS.items():
        problem = problem.replace(f"got {token}", f"found {words}").replace(f"found {token}", f"found {words}")
    loc = Location(file, mark.line + 1, mark.column + 1) if mark else Location(file)
    return Issue(loc, f"YAML syntax error: {problem}{indentation_hint(text, exc.problem or '', mark)}")


def load_yaml(text: str, file: str) -> tuple[Any, SourceMap]:
    """Parse ``text`` (named ``file`` in messages) into plain values and their source map."""
    source = SourceMap(file)
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        raise RecipeError([plain_syntax_error(text, exc, file)]) from None
    except yaml.reader.ReaderError as exc:  # a character YAML does not allow (e.g. a NUL byte)
        line = text.count("\n", 0, exc.position) + 1
        column = exc.position - (text.rfind("\n", 0, exc.position) + 1) + 1
        raise RecipeError(
            [
                Issue(
                    Location(file, line, column),
                    f"character {exc.character!r} is not allowed in YAML",
                    allowed="printable text",
                )
            ]
        ) from None
    except yaml.YAMLError as exc:
        raise RecipeError([Issue(Location(file, 1, 1), f"YAML error: {exc}")]) from None
    if root is None:
        raise RecipeError([Issue(Location(file, 1, 1), "the recipe is empty")])
    issues: list[Issue] = []
    try:
        value = _convert(root, (), source, issues, [MAX_VALUES])
    except _TooLarge as exc:
        raise RecipeError(
            [
                Issue(
                    Location(file, *_mark(exc.node)),
                    f"the document expands to more than {MAX_VALUES:,} values or contains itself (YAML aliases?)",
                    allowed="a recipe without recursive or exploding aliases",
                )
            ]
        ) from None
    except (yaml.YAMLError, ValueError, TypeError, OverflowError) as exc:  # e.g. a malformed timestamp scalar
        raise RecipeError([Issue(Location(file, *_mark(root)), f"YAML value error: {exc}")]) from None
    if issues:
        raise RecipeError(issues)
    return value, source


def nearest_recipe(path: Path) -> str | None:
    """The recipe a missing path most likely meant: ``NAME`` or ``NAME.yaml`` in its folder or in ``graphs/``,
    else the closest name among the .yaml files there."""
    import difflib

    stem = path.name[: -len(".yaml")] if path.name.endswith(".yaml") else path.name
    folders = [path.parent, Path("graphs")] if path.parent != Path("graphs") else [path.parent]
    for folder in folders:
        if (folder / f"{stem}.yaml").is_file():
            return str(folder / f"{stem}.yaml")
    for folder in folders:
        names = sorted(p.stem for p in folder.glob("*.yaml")) if folder.is_dir() else []
        match = difflib.get_close_matches(stem, names, n=1, cutoff=0.6)
        if match:
            return str(folder / f"{match[0]}.yaml")
    return None


def load_yaml_file(path: str | Path) -> tuple[Any, SourceMap]:
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        near = nearest_recipe(path) if isinstance(exc, FileNotFoundError) else None
        raise RecipeError(
            [Issue(Location(str(path)), f"cannot read recipe: {exc.strerror or exc}", suggestion=near)]
        ) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise RecipeError(
            [
                Issue(
                    Location(str(path), line, column),
                    f"the recipe is not UTF-8 text (byte 0x{data[exc.start]:02x})",
                    allowed="a YAML text file in UTF-8",
                )
            ]
        ) from None
    return load_yaml(text, str(path))
