"""The executor interface for independent work: node instances handed to a pool of workers.

A run (or a sweep of runs) is planned as *jobs* (``plan.plan_jobs``), one per node instance that is not
in the cache yet, each naming the cache keys of the jobs it waits for. A pool computes them (``InstancePool``);
every job stores its outputs in the shared content-addressed cache, so when the pool is done the
ordinary in-process run finds everything there and only loads it: outputs, recording and files are
those of an in-process run, bit for bit. Jobs are identified by their cache key, so instances that
several sweep points share are one job.

A job carries how to load the recipe (``RecipeRef``: the file, the overrides, the plugin files, and
the digest the worker checks), not the recipe object: a worker is another process, perhaps on another
machine that sees the same files and the same cache directory. Integrations live in their own modules
behind this interface (``dask_pool``), imported only when asked for.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from . import runtime
from .cache import Cache
from .errors import NodeFailure, NodegraphError
from .executor import Executor
from .plan import Instance, Job, RecipeRef
from .recipe import Recipe, load_recipe
from .registry import default_registry
from .report import NodeRecord, Reporter


@dataclass
class JobResult:
    """What a worker sends back: the instance's record, or the failure's message."""

    key: str
    record: NodeRecord
    error: str | None = None  # the failure as text (a node's own exception need not survive pickling)

    def raise_error(self) -> None:
        if self.error is None:
            return
        if self.record.status == "failed":
            raise RemoteNodeFailure(self.error)
        raise NodegraphError(self.error)


class RemoteNodeFailure(NodeFailure):
    """A node failed on a worker: the message as the worker wrote it (node id, type, cause)."""

    def __init__(self, message: str):
        NodegraphError.__init__(self, message)
        self.node_id = self.node_type = self.cause = self.variant = self.location = None


class InstancePool(Protocol):
    """Computes jobs into the cache at ``cache_dir`` (which its workers share by path); ``compute``
    returns a result per job key (the records of the instances it ran) or raises ``NodegraphError``
    (``RemoteNodeFailure`` for a node that failed), naming the node."""

    def compute(self, jobs: list[Job], cache_dir: Path, reporter) -> dict[str, JobResult]: ...

    def close(self) -> None: ...


_RECIPES: dict[RecipeRef, Recipe] = {}


def load_for_job(ref: RecipeRef) -> Recipe:
    """The recipe a job names, loaded once per worker process; a different digest (the file or the
    code changed under the run) is refused rather than computed under the wrong key."""
    recipe = _RECIPES.get(ref)
    if recipe is None:
        recipe = load_recipe(ref.path, default_registry(plugins=ref.plugins), list(ref.overrides))
        if recipe.digest() != ref.digest:
            raise NodegraphError(f"{ref.path} changed since the run was planned (recipe digest differs); run it again")
        _RECIPES[ref] = recipe
    return recipe


def run_job(job: Job, cache_dir: str, *_upstream) -> JobResult:
    """What a worker does with a job: load the recipe, check the key, compute the instance into the cache.
    The upstream results are passed only so that a scheduler runs this after them. An instance another
    worker finished meanwhile (a retried job) is loaded, not recomputed."""
    runtime.configure()  # numba's kernel cache in this worker process, before the node imports its kernels
    inst = Instance(job.node, job.variant)
    try:
        recipe = load_for_job(job.recipe)
        cache = Cache(cache_dir)
        executor = Executor(recipe, cache, Reporter(quiet=True), max_seconds=job.max_seconds)
        executor.plan({job.node})
        if executor.keys.get(inst) != job.key:
            raise NodegraphError(
                f"node '{job.label}' has another cache key on this worker than where the run was planned "
                "(different code or input files?)"
            )
        executor.hits = {key for key in set(executor.keys.values()) if cache.has(key)}
        if job.key in executor.hits:
            return JobResult(job.key, NodeRecord(job.label, recipe.nodes[job.node].spec.type_name, "cached"))
        executor.materialise(inst)
        return JobResult(job.key, executor.status[inst])
    except NodeFailure as exc:
        return JobResult(job.key, NodeRecord(job.label, exc.node_type or "", "failed"), error=str(exc))
    except NodegraphError as exc:
        return JobResult(job.key, NodeRecord(job.label, "", "not run"), error=str(exc))


class SerialPool:
    """The reference pool: every job in this process, in order (what a Dask run must match)."""

    def compute(self, jobs: list[Job], cache_dir: Path, reporter) -> dict[str, JobResult]:
        results = {}
        for job in jobs:
            if job.key not in results:
                results[job.key] = run_job(job, str(cache_dir))
                results[job.key].raise_error()
        return results

    def close(self) -> None:
        pass


__all__ = ["InstancePool", "JobResult", "RemoteNodeFailure", "SerialPool", "load_for_job", "run_job"]
