"""Independent tasks on several cores, for work that holds the GIL (libigl's signed distance): this process and
forked children take the next task from a shared counter until none is left.

Hand-written because the library pools do not fit: threads run one libigl call at a time (it holds the GIL: the
onigiri's ``measure`` took 8.3 s on two threads against 7.3 s on one), and ``ProcessPoolExecutor`` / ``Pool`` with
the ``spawn`` start method import numpy, scipy and libigl again (≈ 0.5 s) and pickle every element mesh to the
workers. A forked child starts in milliseconds with the parent's meshes already in its memory (copy-on-write), and
sends back only the tasks' small results. Each task's result depends on the task alone, never on which process
ran it or in what order: the merged results are those of a serial run, bit for bit (tests/quality).

A child that fails (an exception, a crash, no ``fork`` on this platform, a daemonic process such as a Dask worker
that may not have children, a child still not done ``LATE_S`` after the last task was taken) only means its tasks
are run here: a task that raises then raises here, as it would serially.

Only the main thread forks. A fork copies the forking thread alone, and the libraries' fork handlers run in it:
OpenBLAS's stops its worker threads, so a matrix product that another thread had under way waited for them forever.
``measure`` runs in the executor's second thread while the preview renders in the main one (``executor.Beside``),
and a fork from there hangs a run in the preview's ``focus_distance``. From any other thread the tasks
run serially, in that thread.
"""

from __future__ import annotations

import multiprocessing
import threading
from collections.abc import Callable, Sequence
from typing import Any

LATE_S = 60.0  # how long after this process has run out of tasks a child may take to send its results


def run_tasks(tasks: Sequence[Callable[[], Any]], processes: int) -> list[Any]:
    """``[task() for task in tasks]``, computed by this process and ``processes − 1`` forked children."""
    if processes <= 1 or len(tasks) < 2 or threading.current_thread() is not threading.main_thread():
        return [task() for task in tasks]
    try:
        context = multiprocessing.get_context("fork")
        counter = context.Value("q", 0)  # the next task to take (with its own lock)
    except (ValueError, OSError):  # no fork on this platform, no shared memory
        return [task() for task in tasks]
    children = []
    finished = False
    try:
        for _ in range(min(processes, len(tasks)) - 1):
            receive, send = context.Pipe(duplex=False)
            child = context.Process(target=_child, args=(tasks, counter, send), daemon=True)
            try:
                child.start()
            except (AssertionError, OSError):  # a daemonic process (a Dask worker) has no children; no memory
                receive.close()
                break
            finally:
                send.close()  # the child holds the sending end: a child that dies closes the pipe
            children.append((child, receive))
        results = {k: tasks[k]() for k in _take(tasks, counter)}
        for child, receive in children:
            try:
                if receive.poll(LATE_S):
                    results |= receive.recv()
                else:  # stuck (no task takes this long): what it took is computed below
                    child.terminate()
            except (EOFError, OSError):  # the child died: what it took is computed below
                pass
        finished = True
    finally:
        for child, receive in children:
            receive.close()
            if not finished:  # a task raised here (or an interrupt): the children's work is not wanted
                child.terminate()
            child.join()
    return [results[k] if k in results else tasks[k]() for k in range(len(tasks))]


def _take(tasks: Sequence, counter):
    """The indices of the tasks this process takes, one at a time, until none is left."""
    while True:
        with counter.get_lock():
            k = counter.value
            counter.value = k + 1
        if k >= len(tasks):
            return
        yield k


def _child(tasks: Sequence[Callable[[], Any]], counter, send) -> None:
    """A forked child: run the tasks it takes, send {index: result} when none is left (nothing if one raises: the
    parent runs those tasks again and raises there)."""
    results = {}
    try:
        for k in _take(tasks, counter):
            results[k] = tasks[k]()
    except Exception:  # quietly: the parent raises it with its traceback
        send.close()
        return
    send.send(results)
    send.close()
