"""Error types a user can act on: what went wrong, where (file:line:column, node, parameter), what is allowed."""

from __future__ import annotations

import os
import pickle
import traceback
from dataclasses import dataclass


@dataclass(frozen=True)
class Location:
    """A place in a recipe file (1-based line and column), or on the command line."""

    file: str
    line: int | None = None
    column: int | None = None

    def __str__(self) -> str:
        if self.line is None:
            return self.file
        if self.column is None:
            return f"{self.file}:{self.line}"
        return f"{self.file}:{self.line}:{self.column}"


@dataclass(frozen=True)
class Issue:
    """One validation problem in a recipe; many are collected and reported together."""

    location: Location
    message: str
    node: str | None = None
    param: str | None = None
    given: object = None
    allowed: str | None = None
    suggestion: str | tuple[str, ...] | None = None  # several: "did you mean 'a' or 'b'?"

    def __str__(self) -> str:
        where = str(self.location)
        subject = ""
        if self.node is not None:
            subject = f"node '{self.node}'"
            if self.param is not None:
                subject += f", {self.param}"
            subject += ": "
        elif self.param is not None:
            subject = f"{self.param}: "
        text = f"{where}: {subject}{self.message}"
        if self.given is not None:
            text += f" (given: {self.given!r})"
        if self.allowed:
            text += f"; allowed: {self.allowed}"
        if self.suggestion:
            names = (self.suggestion,) if isinstance(self.suggestion, str) else self.suggestion
            text += f"; did you mean {' or '.join(f'{n!r}' for n in names)}?"
        return text


class NodegraphError(Exception):
    """Base class of every error the engine raises on purpose."""


class RecipeError(NodegraphError):
    """A recipe failed validation; carries every issue found, not just the first."""

    def __init__(self, issues: list[Issue]):
        self.issues = list(issues)
        count = len(self.issues)
        header = f"{count} problem{'s' if count != 1 else ''} in recipe:"
        super().__init__("\n".join([header, *("  " + str(i) for i in self.issues)]))


class NodeDeclarationError(NodegraphError):
    """A node type is declared inconsistently (a bug in the node module, not in a recipe)."""


class NodeFailure(NodegraphError):
    """A node raised while running; names the node id, its type and the cause."""

    def __init__(
        self,
        node_id: str,
        node_type: str,
        cause: BaseException,
        variant: int | None = None,
        location: Location | None = None,
    ):
        self.node_id = node_id
        self.node_type = node_type
        self.cause = cause
        self.variant = variant
        self.location = location
        label = node_id if variant is None else f"{node_id}[{variant}]"
        where = f"{location}: " if location is not None else ""
        super().__init__(
            f"{where}node '{label}' (type {node_type}) failed: {type(cause).__name__}: {cause}"
            + compiled_cache_hint(cause)
        )


def compiled_cache_hint(cause: BaseException) -> str:
    """A hint when the failure came from loading numba's on-disk cache (a truncated or damaged entry
    fails every run the same way until it is removed)."""
    seen = set()
    while cause is not None and id(cause) not in seen:
        seen.add(id(cause))
        frames = traceback.extract_tb(cause.__traceback__)
        if isinstance(cause, (EOFError, pickle.UnpicklingError)) and any("numba" in f.filename for f in frames):
            directory = os.environ.get("NUMBA_CACHE_DIR", "numba's cache directory")
            return f" — numba's compiled-kernel cache looks damaged: remove {directory} (it is rebuilt on the next run)"
        cause = cause.__cause__ or cause.__context__
    return ""


class CacheCorruption(NodegraphError):
    """A cache entry exists but cannot be trusted (unreadable, truncated, or its hash does not match)."""
