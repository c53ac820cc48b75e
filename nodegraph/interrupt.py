"""Ctrl-C and SIGTERM stop a run within ``GRACE`` seconds, whichever node is running, leaving nothing half-written.

A Python signal handler runs only when the main thread runs Python code: a numba kernel that holds the GIL (say
a neighbour search over a few hundred thousand points: minutes) is deaf to it, and only SIGKILL stopped such a run. So
``nodegraph run``, ``sweep`` and ``watch`` as commands run in a forked child (``supervise``) while the parent, which
does nothing else, waits. On Ctrl-C or SIGTERM the parent passes the signal on; the child stops as before where it
can (finished nodes stay cached); one that has not ended after ``GRACE`` seconds is killed, and the parent removes
what it left half-written.

A step that has finished is stored before it is logged, and stored whole before a stop is honoured (``Hold``): a
signal that comes while the step's result is stored stops the run right after, and the parent waits for it (up to
``HOLD_MAX`` seconds after the signal) rather than killing it after ``GRACE``, so a re-run finds every step that
finished cached; a store still going at ``HOLD_MAX`` is ended, its temporary file removed, and the step is computed
again. A child that has said its 'interrupted' line leaves at once (``leave``): its interpreter's tear-down (threads,
the recording's sinks, freeing memory) took up to a second under load, and the parent's too. So a stop ends within
``HOLD_MAX`` plus the parent's clean-up, whichever node runs (``benchmarks/bench_interrupt.py steps --steps all``).

What a run writes to a temporary or partial name (a recording's ``*.<pid>.partial.rrd``, a node's capture, a file
written by ``cache.atomic_write``) is named here first (``note``): a file in the list that still exists when the
child has ended is an unfinished one (a finished file was renamed into place), and is removed.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

ENV_VAR = "NODEGRAPH_LEFTOVERS"  # set in the child: the file that lists its temporary and partial files
GRACE = 0.8  # seconds the child has to stop by itself after a signal, before it is killed
HOLD_MAX = 1.3  # seconds the parent waits after a signal for a step being stored (``Hold``): 2 s less its clean-up
REPEAT = 0.5  # seconds after a stop in which a second signal is the same stop (Ctrl-C reaches parent and child)


def note(path: str | os.PathLike) -> None:
    """Name a file this process writes under a temporary or partial name, so that a supervising parent removes it
    if the process is killed before it renames or removes it. Nothing without a supervisor."""
    listing = os.environ.get(ENV_VAR)
    if listing:
        with open(listing, "a", encoding="utf-8") as out:
            out.write(os.fspath(path) + "\n")


SAID = "#said"  # a line of the listing, not a file: the child has said that it was interrupted


def said() -> None:
    """Note that this process has printed its 'interrupted' line, so that a supervisor that kills it during its
    clean-up (a second Ctrl-C) does not print a second one."""
    note(SAID)


RUNNING, ENDED = "#running ", "#ended "  # lines of the listing: a step began, a step ended (``step_started``)
HELD, FREED = "#holding ", "#stored "  # lines of the listing: a finished step is being stored, and is (``Hold``)
SAVED = "#saved "  # a line of the listing: a step saved its progress (``progress_saved``): its file, and where it is
UNCACHED = "#uncached"  # a line of the listing: the run keeps nothing that finishes (--no-cache)

# the steps running now in this process (label: (start, checkpoint file or None)), and whether the run keeps what
# finishes (a cache): what a re-run would find
_running: dict[str, tuple[float, Path | None]] = {}
_saved: dict[Path, str] = {}  # checkpoint file: where its saved progress is ("frame 1,200"; "" where not known)
# cached None: no run has begun in this process; command: the command line after ``nodegraph`` (``said_command``)
_run: dict = {"cached": None, "stopping": False, "command": ()}
_held = {"count": 0, "pending": False}  # the main thread's holds open now, and whether a stop waits for them


def run_began(cached: bool) -> None:
    """A run begins: whether it keeps what finishes (a cache) decides what its 'interrupted' line promises."""
    _running.clear()
    _run["cached"] = cached
    _run["stopping"] = False
    if not cached:
        note(UNCACHED)


def step_started(label: str, checkpoint: Path | None = None) -> None:
    """A step (node instance) starts computing; ``checkpoint``: the file it saves its progress to, if any."""
    _running[label] = (time.monotonic(), checkpoint)
    note(RUNNING + label + ("" if checkpoint is None else f"\t{checkpoint}"))


def progress_saved(checkpoint: Path, where: str = "") -> None:
    """A step saved its progress to ``checkpoint``; ``where``: how far it was ("frame 1,200"), if known."""
    _saved[Path(checkpoint)] = where
    note(SAVED + f"{checkpoint}\t{where}")


def _resumes(label: str, checkpoint: Path | None, saved: dict[Path, str]) -> str | None:
    """What a stopped step keeps for a re-run ("rice_sim's progress up to frame 1,200"), or None."""
    if checkpoint is None or not Path(checkpoint).exists():
        return None
    where = saved.get(Path(checkpoint), "")
    return f"{label}'s progress" + (f" up to {where}" if where else " so far")


def said_command(argv: list[str]) -> None:
    """Keep the command line (``run graphs/ikura_don.yaml --draft``) that a stopped run tells the user to repeat."""
    _run["command"] = tuple(argv)


def _again() -> str:
    """The command that resumes: this one again, as typed."""
    import shlex

    return "the same command again" + (f": nodegraph {shlex.join(_run['command'])}" if _run["command"] else "")


def _rerun(uncached: bool, running: dict[str, Path | None], saved: dict[Path, str]) -> str:
    """What a stopped run kept and how to resume, in plain words: nothing without a cache, else every finished step
    and each running step's saved progress (``running``: label → its checkpoint file or None)."""
    if uncached:
        return f"Nothing was kept (--no-cache). To start over, run {_again()}"
    resumes = [r for label, checkpoint in running.items() if (r := _resumes(label, checkpoint, saved))]
    return (
        "Kept: every step that finished (in the cache)"
        + (f" and {' and '.join(resumes)}" if resumes else "")
        + f". To resume from there, run {_again()}"
    )


class Hold:
    """While a finished step's result is logged and stored (``with Hold(label):``), a stop signal waits: the
    main thread's handler notes it (``stop``) and it is raised as the hold ends, once the result is stored; the
    supervising parent, which reads the hold in the listing, does not kill the process meanwhile (``HOLD_MAX``).
    Held in another thread (a step computed beside another), only the parent waits: the main thread stops at
    once and waits for that thread's step (``executor.Beside``)."""

    def __init__(self, label: str):
        self.label = label
        self.main = threading.current_thread() is threading.main_thread()

    def __enter__(self) -> Hold:
        note(HELD + self.label)
        if self.main:
            _held["count"] += 1
        return self

    def __exit__(self, kind, exc, tb) -> None:
        note(FREED + self.label)
        if not self.main:
            return
        _held["count"] -= 1
        if _held["count"] == 0 and _held["pending"]:
            _held["pending"] = False
            if kind is None:  # stored: the stop that came meanwhile is honoured now
                raise KeyboardInterrupt


def pending() -> bool:
    """Whether a stop waits for the main thread's hold to end (a store then writes what is quickest to write)."""
    return bool(_held["pending"])


def leave(status: int) -> None:
    """End a supervised child at once with ``status``, its output flushed: what it had to do is done (files
    renamed into place or named in the listing, its line said), and its interpreter's tear-down (joining threads,
    the recording's sinks, freeing memory) took up to a second under load. Returns where nothing supervises it."""
    if not os.environ.get(ENV_VAR):
        return
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


def step_ended(label: str) -> None:
    """A step has ended (done, failed or stopped)."""
    _running.pop(label, None)
    note(ENDED + label)


def stopped_line() -> str:
    """The one line a stopped run prints: the step(s) it stopped in, and what a re-run starts from."""
    now = time.monotonic()
    where = ", ".join(f"{label} ({now - start:.0f} s in)" for label, (start, _) in _running.items())
    head = f"interrupted during {where}" if where else "interrupted"
    if _run["cached"] is None:
        return f"{head} before any step ran: nothing was computed. To start, run {_again()}"
    checkpoints = {label: checkpoint for label, (_, checkpoint) in _running.items()}
    return f"{head}. {_rerun(not _run['cached'], checkpoints, _saved)}"


def running_in(listing: Path) -> list[str]:
    """The steps the listing shows started and not ended (what a killed child was running)."""
    return list(_listed(listing)[0])


def holding(listing: Path) -> bool:
    """Whether the listing shows a finished step being stored now (``Hold``)."""
    return bool(_listed(listing)[2])


def _listed(listing: Path) -> tuple[dict[str, Path | None], dict[Path, str], set[str]]:
    """The steps the listing shows started and not ended, each with its checkpoint file (or None); where each
    checkpoint file's saved progress is (``progress_saved``); the finished steps being stored now (``Hold``)."""
    try:
        lines = listing.read_text(encoding="utf-8").splitlines()
    except OSError:
        return {}, {}, set()
    running: dict[str, Path | None] = {}
    saved: dict[Path, str] = {}
    held: set[str] = set()
    for line in lines:
        if line.startswith(RUNNING):
            label, _, checkpoint = line[len(RUNNING) :].partition("\t")
            running[label] = Path(checkpoint) if checkpoint else None
        elif line.startswith(ENDED):
            running.pop(line[len(ENDED) :], None)
        elif line.startswith(SAVED):
            checkpoint, _, where = line[len(SAVED) :].partition("\t")
            saved[Path(checkpoint)] = where
        elif line.startswith(HELD):
            held.add(line[len(HELD) :])
        elif line.startswith(FREED):
            held.discard(line[len(FREED) :])
    return running, saved, held


NAMED = 3  # at most this many removed files are named in the line of a killed run; the rest are counted


def killed_line(listing: Path, removed: list[Path], waited: float = GRACE) -> str:
    """The line of a run killed ``waited`` seconds after the stop: the steps it was in, the unfinished files removed
    (the first ``NAMED``), what a re-run resumes from (a step's saved checkpoint, with how far it was)."""
    running, saved, _ = _listed(listing)
    during = f" during {', '.join(running)}" if running else ""
    who = "the run" if not running else ("the step" if len(running) == 1 else "the steps")
    what = ""
    if removed:
        names = ", ".join(str(p) for p in removed[:NAMED])
        more = f" and {len(removed) - NAMED} more" if len(removed) > NAMED else ""
        what = f"; removed {len(removed)} unfinished file(s): {names}{more}"
    try:
        lines = listing.read_text(encoding="utf-8").splitlines()
    except OSError:
        lines = []
    if not any(line.startswith(RUNNING) for line in lines):  # ended as it started (imports, the recipe's checks)
        return (
            f"interrupted before any step ran: the run did not stop within {waited:g} s and was ended{what}. "
            f"Nothing was computed. To start, run {_again()}"
        )
    rerun = _rerun(UNCACHED in lines, running, saved)
    ended = "were ended" if len(running) > 1 else "was ended"
    return f"interrupted{during}: {who} did not stop within {waited:g} s and {ended}{what}. {rerun}"


def remove_leftovers(listing: Path) -> list[Path]:
    """Remove the files named in ``listing`` that still exist (what a killed run left unfinished), then the folders
    named there that are left empty (made for outputs the stopped run never wrote); the files removed."""
    try:
        names = listing.read_text(encoding="utf-8").splitlines()
    except OSError:
        return []
    removed, folders = [], []
    for name in dict.fromkeys(names):
        path = Path(name)
        if name in (SAID, UNCACHED) or name.startswith((RUNNING, ENDED, SAVED, HELD, FREED)):
            continue
        if path.is_dir():
            folders.append(path)
            continue
        try:
            path.unlink()
        except OSError:
            continue
        removed.append(path)
    for folder in sorted(folders, key=lambda f: len(f.parts), reverse=True):
        with contextlib.suppress(OSError):  # not empty: something was written there
            folder.rmdir()
    return removed


def was_said(listing: Path) -> bool:
    """Whether the child noted that it printed its 'interrupted' line (``said``)."""
    try:
        return SAID in listing.read_text(encoding="utf-8").splitlines()
    except OSError:
        return False


_stopped_at: float | None = None


def repeated() -> bool:
    """Whether a stop signal repeats one of the last ``REPEAT`` seconds (Ctrl-C at a terminal reaches the child and
    the parent, which passes it on too: one stop, not a second interrupting the first's cleanup); notes this one."""
    global _stopped_at
    now = time.monotonic()
    again = _stopped_at is not None and now - _stopped_at < REPEAT
    if not again:
        _stopped_at = now
    return again


def stopping() -> None:
    """Note that a stop (SIGINT, SIGTERM) reached this process: an error a node raises from now on is the stop's
    doing (``stopped_by``)."""
    _run["stopping"] = True


def stopped_by(exc: BaseException) -> bool:
    """Whether ``exc``, raised by a node, is a stop rather than a failure: a stop reached this process while the
    run went on, or a ``KeyboardInterrupt`` is in its chain. A signal's handler raises in whatever code runs: in a
    call into compiled code (numba's dispatcher) it comes out as another error, as "SystemError: CPUDispatcher(...)
    returned a result with an exception set", which is no failure of the node."""
    if _run["stopping"]:
        return True
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def stop(signum, frame) -> None:
    """The child's handler of SIGINT and SIGTERM: a ``KeyboardInterrupt``, once per stop (``repeated``); while
    a finished step is stored (``Hold``), as that ends."""
    stopping()
    if repeated():
        return
    if _held["count"]:
        _held["pending"] = True
        return
    raise KeyboardInterrupt


def quiet_stops(unraisable) -> None:
    """``sys.unraisablehook`` of a supervised run: a stop raised where Python can only report it (a callback from
    compiled code, such as numba's compiler's into LLVM) is already noted (``stopping``) and the run stops as
    ever, so it prints nothing; anything else is reported as Python would."""
    if not issubclass(unraisable.exc_type, KeyboardInterrupt):
        sys.__unraisablehook__(unraisable)


def supervise(child_signals: bool = True) -> int | None:
    """In the parent: fork, and return the child's exit status once it has ended (killed after ``GRACE`` seconds
    if a signal did not stop it). In the child: None, the command to be run by the caller. None, too, where there
    is no ``fork`` (Windows: the command runs in this process, as before). ``child_signals``: a SIGINT or SIGTERM
    sent to the child alone is a stop too (False for a child that signals itself, as ``watch`` does)."""
    if not hasattr(os, "fork") or os.environ.get(ENV_VAR):
        return None
    fd, name = tempfile.mkstemp(prefix="nodegraph-leftovers-", suffix=".txt")
    os.close(fd)
    listing = Path(name)
    parent = os.getpid()
    # the child's signals, as Python's C-level handler sees them (``signal.set_wakeup_fd``): written at once, even
    # while a kernel holds the GIL, so a signal sent to the child alone (``kill PID`` of the process that computes)
    # is held to GRACE seconds too; the child's own handler would run only after the kernel, or it may wait for ever
    # in its clean-up
    news, word = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:
        os.environ[ENV_VAR] = name
        _die_with(parent)
        os.close(news)
        if child_signals:
            os.set_blocking(word, False)
            signal.set_wakeup_fd(word, warn_on_full_buffer=False)
        else:
            os.close(word)
        signal.signal(signal.SIGINT, stop)
        signal.signal(signal.SIGTERM, stop)
        sys.unraisablehook = quiet_stops
        return None
    os.close(word)
    try:
        return _wait(pid, listing, news)
    finally:
        os.close(news)
        listing.unlink(missing_ok=True)


def _die_with(parent: int) -> None:
    """Have the kernel kill this child if the parent dies first (SIGKILL to the parent: nothing is left running)."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG (Linux)
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the parent died before the request was made
        os._exit(1)


def _wait(pid: int, listing: Path, news: int) -> int:
    received: list[float] = []  # when each signal to this process came
    stops: list[float] = []  # when a stop began: a signal to this process or to the child
    os.set_blocking(news, False)

    def forward(signum, frame) -> None:
        received.append(time.monotonic())
        stops.append(received[-1])
        try:
            os.kill(pid, signum)
        except ProcessLookupError:
            pass

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, forward)
    killed = False
    status = None
    held = False  # a finished step was seen being stored after the stop: it has up to HOLD_MAX seconds
    while status is None:
        try:
            if {signal.SIGINT, signal.SIGTERM} & set(os.read(news, 64)):
                stops.append(time.monotonic())
        except BlockingIOError:
            pass
        done, code = os.waitpid(pid, os.WNOHANG)
        if done:
            status = code
            break
        # a second Ctrl-C: at once; else GRACE seconds after the stop, HOLD_MAX where a finished step was being
        # stored (``Hold``)
        if stops and not killed:
            held = held or holding(listing)
            if len(received) > 1 or time.monotonic() - min(stops) > (HOLD_MAX if held else GRACE):
                os.kill(pid, signal.SIGKILL)
                killed = True
        time.sleep(0.02)
    # stopped or killed: what it left unfinished goes; a run that ended by itself (done, or failed: its partial
    # recording kept for what the failing node logged, as it says) cleaned up after itself
    told = was_said(listing)
    removed = remove_leftovers(listing) if stops or os.WIFSIGNALED(status) else []
    if killed and told:  # the child said it was interrupted before it was ended in its clean-up
        return 130
    if killed:
        if sys.stderr.isatty():
            sys.stderr.write("\x1b[?25h\n")  # the progress bar hid the cursor
        print(killed_line(listing, removed, HOLD_MAX if held else GRACE), file=sys.stderr)
        return 130
    return os.WEXITSTATUS(status) if os.WIFEXITED(status) else 128 + os.WTERMSIG(status)
