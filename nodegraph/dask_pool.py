"""Dask distributed behind the pool interface (``pool.InstancePool``): node instances as Dask tasks.

``DaskPool(address)`` connects to a running scheduler (``dask scheduler`` + ``dask worker ADDRESS``
on each machine); ``DaskPool(workers=N)`` starts a LocalCluster of N single-threaded worker
processes here, each with ``NUMBA_NUM_THREADS`` = cores // N so that numba threads × workers stay
within the cores. A task is one node instance (``pool.run_job``) and waits for the tasks of its
inputs; its Dask key is the cache key, so instances that several sweep points share run once.
Workers read and write the cache by path (a shared filesystem on a cluster): an entry is written
atomically, so a worker that dies mid-node leaves no partial entry, and the scheduler runs the task
again on another worker. A node that fails is not retried (it would fail the same way).

Needs ``pip install "dask[distributed]"``; without it only this module fails, with that message.
"""

from __future__ import annotations

import os
from pathlib import Path

from .errors import NodegraphError
from .plan import Job
from .pool import JobResult, run_job


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise NodegraphError(
            '--scheduler and --workers need Dask distributed: pip install "dask[distributed]"'
        ) from None
    return distributed


def worker_threads(workers: int, cores: int | None = None) -> int:
    """numba threads per worker so that threads × workers stay within the cores (at least 1)."""
    return max(1, (cores or os.cpu_count() or 1) // max(1, workers))


def _worker_facts() -> dict:
    import socket

    import numba

    return {"host": socket.gethostname(), "cores": os.cpu_count(), "numba_threads": numba.get_num_threads()}


class DaskPool:
    """Node instances computed on a Dask cluster; see the module docstring."""

    def __init__(self, address: str | None = None, workers: int | None = None, warn=None):
        distributed = _import_distributed()
        self.cluster = None
        if address:
            try:
                self.client = distributed.Client(address, timeout="20s")
            except OSError as exc:
                raise NodegraphError(f"--scheduler {address}: cannot connect ({exc})") from None
        else:
            if not workers or workers < 1:
                raise NodegraphError(f"--workers {workers}: give at least 1")
            threads = str(worker_threads(workers))
            self.cluster = distributed.LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                env={"NUMBA_NUM_THREADS": threads, "OMP_NUM_THREADS": threads},
            )
            self.client = distributed.Client(self.cluster)
        if warn is not None:
            self._check_threads(warn)

    @property
    def description(self) -> str:
        workers = self.client.scheduler_info(n_workers=-1).get("workers", {})
        kind = "LocalCluster" if self.cluster is not None else self.client.scheduler.address
        return f"Dask {kind}, {len(workers)} worker(s)"

    def _check_threads(self, warn) -> None:
        """Warn when numba threads × workers on a host exceed its cores (workers started by hand)."""
        try:
            facts = self.client.run(_worker_facts)
        except Exception:  # a worker leaving now is the scheduler's business, not a reason to stop
            return
        hosts: dict[str, list[dict]] = {}
        for fact in facts.values():
            hosts.setdefault(fact["host"], []).append(fact)
        for host, items in hosts.items():
            threads = sum(f["numba_threads"] for f in items)
            if threads > items[0]["cores"]:
                warn(
                    f"{len(items)} Dask worker(s) on {host} run {threads} numba threads on {items[0]['cores']} "
                    f"cores; start them with NUMBA_NUM_THREADS={worker_threads(len(items), items[0]['cores'])}"
                )

    def compute(self, jobs: list[Job], cache_dir: Path, reporter) -> dict[str, JobResult]:
        distributed = _import_distributed()
        futures: dict[str, object] = {}
        for job in jobs:
            if job.key in futures:
                continue
            upstream = [futures[k] for k in job.needs if k in futures]
            futures[job.key] = self.client.submit(
                run_job, job, str(Path(cache_dir).resolve()), *upstream, key=f"{job.label}-{job.key}", pure=False
            )
        results: dict[str, JobResult] = {}
        try:
            with reporter.task(f"{len(futures)} node instances on {self.description}", len(futures)) as tick:
                for future in distributed.as_completed(list(futures.values())):
                    tick()
                    try:
                        result = future.result()
                    except distributed.KilledWorker as exc:
                        raise NodegraphError(f"Dask gave up on a task: workers died running it ({exc})") from None
                    result.raise_error()
                    results[result.key] = result
        finally:
            for future in futures.values():
                future.cancel()
        return results

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()

    def __enter__(self) -> DaskPool:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


__all__ = ["DaskPool", "worker_threads"]
