"""The engine in a few calls, for tests, notebooks and benchmarks."""

from __future__ import annotations

from .cache import Cache, default_cache_dir
from .executor import Executor, RunResult, run_recipe
from .plan import Instance
from .recipe import Recipe, load_recipe, parse_recipe
from .registry import Registry, default_registry

__all__ = [
    "Cache",
    "Executor",
    "Instance",
    "Recipe",
    "Registry",
    "RunResult",
    "default_cache_dir",
    "default_registry",
    "load_recipe",
    "parse_recipe",
    "run_recipe",
]
