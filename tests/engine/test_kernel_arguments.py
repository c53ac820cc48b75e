"""No function in nodes/ or nodegraph/ takes more than 12 parameters (issue 23): a kernel that needs more
takes named bundles (typed named tuples, as ``refine_kernels.ElementFrames``), so an order slip between
two same-typed arrays cannot happen. Node functions are aside: their declared inputs and parameters arrive
as keywords, and the ``@node(...)`` declaration names each one."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LIMIT = 12


def _is_node_function(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """Decorated with ``@node(...)`` (nodegraph.node.node): its parameters are the node's declared ports."""
    for decorator in fn.decorator_list:
        call = decorator.func if isinstance(decorator, ast.Call) else None
        if isinstance(call, ast.Name) and call.id == "node" or isinstance(call, ast.Attribute) and call.attr == "node":
            return True
    return False


def wide_functions(root: Path = ROOT) -> dict[tuple[str, str], tuple[int, int]]:
    """(file, function) → (line, parameter count), for every function over ``LIMIT`` that is not a node function."""
    found = {}
    for package in ("nodes", "nodegraph"):
        for path in sorted((root / package).rglob("*.py")):
            for fn in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef) and not _is_node_function(fn):
                    a = fn.args
                    count = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + bool(a.vararg) + bool(a.kwarg)
                    if count > LIMIT:
                        found[(path.relative_to(root).as_posix(), fn.name)] = (fn.lineno, count)
    return found


def test_no_function_takes_more_than_12_parameters():
    offenders = sorted(f"{path}:{line} {name} ({count})" for (path, name), (line, count) in wide_functions().items())
    assert not offenders, (
        f"functions with more than {LIMIT} parameters: {offenders}; pass named bundles "
        "(typing.NamedTuple of arrays: numba takes them as one argument)"
    )


def test_node_functions_are_recognised_and_nothing_else(tmp_path):
    """The scan excepts ``@node(...)`` functions only: a plain function or one under another decorator counts."""
    package = tmp_path / "nodes"
    package.mkdir()
    (tmp_path / "nodegraph").mkdir()
    args = ", ".join(f"a{k}" for k in range(LIMIT + 1))
    (package / "wide.py").write_text(
        f"@node('x', outputs={{}})\ndef declared(ctx, {args}): ...\n\n"
        f"@njit(cache=True)\ndef kernel({args}): ...\n\n"
        f"def narrow({', '.join(f'a{k}' for k in range(LIMIT))}): ...\n"
    )
    assert wide_functions(tmp_path) == {("nodes/wide.py", "kernel"): (5, LIMIT + 1)}
