"""What a run tells its user: progress bars for long nodes, and a closing table per node instance."""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rich.console import Console

if TYPE_CHECKING:  # drawn only on a terminal, or printed without -q: loaded then (a cached re-run needs neither)
    from rich.progress import Progress
    from rich.table import Table

_PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096


def _rss_bytes() -> int | None:
    try:
        with open("/proc/self/statm", "rb") as handle:
            return int(handle.read().split()[1]) * _PAGE
    except (OSError, ValueError, IndexError):
        return None


def _reset_peak() -> bool:
    """Reset the kernel's resident high-water mark of this process to its present size (Linux ≥ 4.0:
    ``clear_refs`` 5); False where it cannot be done."""
    try:
        with open("/proc/self/clear_refs", "wb") as handle:
            handle.write(b"5")
        return True
    except OSError:
        return False


def _peak_rss_bytes() -> int | None:
    """The resident high-water mark (``VmHWM``) since the process started or ``_reset_peak``."""
    try:
        with open("/proc/self/status", "rb") as handle:
            for line in handle:
                if line.startswith(b"VmHWM:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


class PeakMemory:
    """Peak resident memory above the start value while a block runs (Linux).

    The kernel's high-water mark, reset as the block starts: exact, and nothing runs meanwhile (a thread
    sampling /proc every 5 ms cost 3 % of a core while the node ran, more wall under load, and took the GIL
    from the node 200 times a second). Where the mark cannot be reset, sampled every ``interval`` s.
    """

    def __init__(self, interval: float = 0.005):
        self.interval = interval
        self.peak_bytes: int | None = None
        self._thread = None

    def __enter__(self) -> PeakMemory:
        self._start = _rss_bytes()
        self._peak = self._start
        if self._start is not None and not _reset_peak():
            self._stop = threading.Event()
            self._thread = threading.Thread(target=self._sample, daemon=True)
            self._thread.start()
        return self

    def _sample(self) -> None:
        while not self._stop.wait(self.interval):
            rss = _rss_bytes()
            if rss is not None and rss > self._peak:
                self._peak = rss

    def __exit__(self, *exc) -> None:
        if self._start is None:
            return
        if self._thread is None:
            self._peak = _peak_rss_bytes() or self._peak
        else:
            self._stop.set()
            self._thread.join()
        end = _rss_bytes() or self._peak
        self.peak_bytes = max(0, self._peak - self._start, end - self._start)  # a node that freed more than it took: 0


_COLOUR = {"ran": "green", "cached": "cyan", "failed": "red"}
PIPE_WIDTH = 10_000  # columns a table may take where no terminal sets a width (a pipe, a log): no cell is cut
# a node's peak memory below this is noise (the allocator's arenas, pages another thread frees while it runs: a node
# that allocates nothing has shown -0.2 MiB): shown as "< 1 MiB"
MEMORY_NOISE = 2**20
HEARTBEAT_ENV = "NODEGRAPH_HEARTBEAT"  # seconds: sooner or later than HEARTBEAT_S (a CI log, a benchmark)
# where no bar is drawn, a step running this long is said to be running, and again every HEARTBEAT_EVERY_S after:
# a log shows that a long step is alive, without flooding
try:
    HEARTBEAT_S = float(os.environ.get(HEARTBEAT_ENV) or 10.0)
except ValueError:  # not a number: the default, as where it is unset
    HEARTBEAT_S = 10.0
HEARTBEAT_EVERY_S = 30.0
# where no bar is drawn (a pipe, a log), a step is said as it ends, and listed in the closing table, only when it
# took this long or failed: a cold run of the main job printed ≈ 200 lines, its 97 steps mostly milliseconds each;
# the others are named in one line under the table
PLAIN_SHOWN_S = 1.0


@dataclass
class NodeRecord:
    """One row of the closing table."""

    node: str
    type: str
    status: str  # ran | cached | failed | recomputed (corrupt cache)
    seconds: float = 0.0
    peak_bytes: int | None = None
    log_seconds: float | None = None  # logging its outputs to Rerun (None: no recording)
    cpu_seconds: float | None = None  # the process's CPU time while it ran, all threads (None: not run here;
    # beside a node declared overlap: the second thread's own, and the rest to that node, executor.Beside)


class Reporter:
    """Collects node records; shows progress bars on a terminal, prints the table at the end."""

    def __init__(self, console: Console | None = None, quiet: bool = False):
        self.console = console or Console(stderr=True)
        self.quiet = quiet
        self.records: list[NodeRecord] = []
        self._progress: Progress | None = None
        # where no bar is drawn (a pipe, CI, ``| tee``): a plain line per step as it ends, a heartbeat per long one
        self.plain = not quiet and not self.console.is_terminal
        # in plain output, the closing table lists only the steps that took ``PLAIN_SHOWN_S`` or more and names the
        # rest under it (a watch lists every step: what each save re-ran)
        self.fold = True
        self._running: dict[str, tuple[float, float]] = {}  # label: (started, when to say it is still running)
        self._lock = threading.Lock()
        self._heart: threading.Thread | None = None

    def record(self, record: NodeRecord) -> None:
        self.records.append(record)

    def _say(self, line: str) -> None:
        self.console.print(line, soft_wrap=True, highlight=False, markup=False)

    def step_started(self, label: str) -> None:
        """A step (node instance) starts computing: in plain output, its heartbeat is due after ``HEARTBEAT_S``."""
        if not self.plain:
            return
        with self._lock:
            started = time.monotonic()
            self._running[label] = (started, started + HEARTBEAT_S)
            if self._heart is None:
                self._heart = threading.Thread(target=self._beat, name="nodegraph-heartbeat", daemon=True)
                self._heart.start()

    def step_ended(self, label: str, seconds: float, ok: bool) -> None:
        """A step has computed (``ok``) or failed: one plain line where no bar is drawn."""
        if not self.plain:
            return
        with self._lock:
            self._running.pop(label, None)
        if ok and seconds < PLAIN_SHOWN_S:
            return
        self._say(f"{label}: {'done' if ok else 'failed'} in {format_duration(seconds)}")

    def _beat(self) -> None:
        """Say every step running past its due time (``step_started``); ends when none is running."""
        while True:
            time.sleep(min(1.0, HEARTBEAT_S / 4))
            now = time.monotonic()
            with self._lock:
                if not self._running:
                    self._heart = None
                    return
                due = [(label, now - started) for label, (started, at) in self._running.items() if now >= at]
                for label, _ in due:
                    self._running[label] = (self._running[label][0], now + HEARTBEAT_EVERY_S)
            for label, running in due:
                self._say(f"{label}: running, {running:.0f} s so far")

    def warn(self, message: str) -> None:
        if not self.quiet:
            # soft wrap: a hard wrap at the console's width breaks paths and phrases in pipes and logs
            self.console.print(f"[yellow]warning:[/yellow] {message}", soft_wrap=True)

    def info(self, message: str) -> None:
        if not self.quiet:
            self.console.print(message, soft_wrap=True)

    def tell(self, message: str) -> None:
        """Say ``message`` even with -q: what a run did to files the user has seen (removed them)."""
        self.console.print(message, soft_wrap=True, highlight=False, markup=False)

    @contextlib.contextmanager
    def task(self, description: str, total: int, plan: list[float | None] | None = None) -> Iterator:
        """A progress bar; only drawn on an interactive terminal so logs in CI stay clean.

        Bars nest (the run's bar over node instances, a node's bar over frames) inside one rich
        live display, since rich allows only one at a time. ``plan``: the seconds each step is expected to take
        (None: not known), the first tick starting the first step; the bar's ETA is then their sum still ahead
        (``remaining_seconds``), not the pace of the steps so far (a run's 97 steps: 93 quick, then a minute's
        preview read "93/97 … eta 0:00:02").
        """
        if self.quiet or not self.console.is_terminal:
            yield lambda amount=1: None
            return
        owner = self._progress is None
        if owner:
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._progress = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TimeElapsedColumn(),
                TextColumn("eta"),
                _PlannedRemaining(TimeRemainingColumn()),
                console=self.console,
                transient=True,
            )
            self._progress.start()
        progress = self._progress
        task_id = progress.add_task(description, total=total, plan=plan, since=None)
        try:
            if plan is None:
                yield lambda amount=1: progress.advance(task_id, amount)
            else:
                yield lambda amount=1: progress.update(task_id, advance=amount, since=time.monotonic())
        finally:
            progress.remove_task(task_id)
            if owner:
                progress.stop()
                self._progress = None

    def summary(self, per_instance: bool = False, width: int | None = None, shown_s: float = 0.0) -> Table:
        """One row per node (variant families folded into one row, times summed) or per instance, in ``width``
        columns (default: the console's; 80 in a pipe): the type column goes where the table would not fit
        (``nodegraph graph`` names each node's type), and no cell wraps. ``shown_s``: only the rows that took at
        least this long or failed, the rest counted in the caption."""
        from rich.table import Table

        logged = any(r.log_seconds is not None for r in self.records)
        rows: dict[str, list[NodeRecord]] = {}
        for rec in self.records:
            rows.setdefault(rec.node if per_instance else rec.node.split("[")[0], []).append(rec)
        hidden = {
            node: records
            for node, records in rows.items()
            if sum(r.seconds for r in records) < shown_s and all(r.status != "failed" for r in records)
        }
        rows = {node: records for node, records in rows.items() if node not in hidden}
        cells = []
        for node, records in rows.items():
            counts: dict[str, int] = {}
            for rec in records:
                counts[rec.status] = counts.get(rec.status, 0) + 1
            status = [(s, f" ×{n}" if len(records) > 1 else "") for s, n in counts.items()]
            peaks = [r.peak_bytes for r in records if r.peak_bytes is not None]
            cpu = [r.cpu_seconds for r in records if r.cpu_seconds is not None]
            row = [
                node,
                records[0].type,
                status,
                format_duration(sum(r.seconds for r in records)),
                format_duration(sum(cpu)) if cpu else "",
                format_peak(max(peaks)) if peaks else "",
            ]
            if logged:
                row.append(format_duration(sum(r.log_seconds or 0.0 for r in records)))
            cells.append(row)
        columns = [
            ("node", "left"),
            ("type", "left"),
            ("status", "left"),
            ("wall time", "right"),
            ("CPU time", "right"),
            ("peak mem", "right"),
        ] + ([("rerun log", "right")] if logged else [])

        def text(cell) -> str:
            return "".join(s + n for s, n in cell) if isinstance(cell, list) else cell

        widths = [max([len(name)] + [len(text(row[i])) for row in cells]) for i, (name, _) in enumerate(columns)]
        room = self.console.width if width is None else width
        keep = [i for i in range(len(columns)) if i != 1 or sum(widths) + 3 * len(columns) + 1 <= room]
        table = Table(title="nodegraph run")
        if hidden:
            table.caption = _hidden_line(hidden, shown_s, more=bool(rows))
        for i in keep:
            table.add_column(columns[i][0], justify=columns[i][1], no_wrap=True)
        for row in cells:
            shown = [
                ", ".join(f"[{_COLOUR.get(s, 'yellow')}]{s}[/]{n}" for s, n in row[i]) if i == 2 else row[i]
                for i in keep
            ]
            table.add_row(*shown)
        return table

    def print_summary(self) -> None:
        """The table: on a terminal, fitted to its width; in a pipe or a log, which have no width, whole (every
        column, no cell cut: "wall ti…" told nothing) but short, the steps under ``PLAIN_SHOWN_S`` counted in a
        line."""
        if self.quiet or not self.records:  # nothing ran or loaded: no table with no rows
            return
        if self.console.is_terminal:
            self.console.print(self.summary())
            return
        from rich.measure import Measurement

        table = self.summary(width=PIPE_WIDTH, shown_s=PLAIN_SHOWN_S if self.fold else 0.0)
        needed = Measurement.get(self.console, self.console.options.update(width=PIPE_WIDTH), table).maximum
        width = self.console.width
        self.console.width = max(width, needed)  # rich cuts whatever is wider than its console
        try:
            if table.row_count:
                self.console.print(table)
            else:  # every step folded into the caption: the caption alone, not an empty table above it
                self._say(str(table.caption))
        finally:
            self.console.width = width


def remaining_seconds(plan: list[float | None], started: int, since: float | None, now: float) -> tuple[float, bool]:
    """Seconds still ahead when ``started`` steps of ``plan`` have begun, the last at ``since``: the expected
    seconds of the steps not begun, and of the one running what is left of it (none once it has overrun). Also
    whether every step's cost is known (else the figure is a lower bound)."""
    ahead = plan[started:]
    known = all(seconds is not None for seconds in ahead)
    total = sum(seconds or 0.0 for seconds in ahead)
    if started and since is not None:
        running = plan[started - 1]
        known = known and running is not None
        total += max(0.0, (running or 0.0) - (now - since))
    return total, known


class _PlannedRemaining:
    """The ETA column: from the plan of a task that has one (``Reporter.task``), else rich's own (``fallback``)."""

    def __init__(self, fallback):
        self.fallback = fallback

    def __getattr__(self, name):  # the rest of rich's column protocol
        return getattr(self.fallback, name)

    def __call__(self, task):
        from rich.text import Text

        plan = task.fields.get("plan")
        if plan is None:
            return self.fallback(task)
        seconds, known = remaining_seconds(plan, int(task.completed), task.fields.get("since"), time.monotonic())
        if not known and seconds == 0.0:  # nothing ahead is known: no figure (a count's would mislead)
            return Text("-:--:--", style="progress.remaining")
        minutes, rest = divmod(int(round(seconds)), 60)
        text = f"{minutes // 60}:{minutes % 60:02d}:{rest:02d}"
        return Text(text if known else f"≥ {text}", style="progress.remaining")


def format_duration(seconds: float) -> str:
    """A time in at most 7 characters: 0.2 ms, 35 ms, 1.23 s, 85.1 s, 12m05s, 3h05m."""
    if seconds < 0.01:
        return f"{seconds * 1000:.1f} ms"
    if seconds < 1:
        return f"{seconds * 1000:.0f} ms"
    if seconds < 10:
        return f"{seconds:.2f} s"
    if seconds < 100:
        return f"{seconds:.1f} s"
    if seconds < 3600:
        return f"{int(seconds // 60)}m{int(seconds % 60):02d}s"
    return f"{int(seconds // 3600)}h{int(seconds % 3600 // 60):02d}m"


def parse_duration(text: str) -> float:
    """Seconds from ``format_duration``'s text (a tool that reads the closing table)."""
    import re

    found = re.fullmatch(r"([\d.]+) (ms|s)|(\d+)m(\d+)s|(\d+)h(\d+)m", text.strip())
    if found is None:
        raise ValueError(f"not a duration: {text!r}")
    number, unit, minutes, seconds, hours, hour_minutes = found.groups()
    if number is not None:
        return float(number) / (1000 if unit == "ms" else 1)
    if minutes is not None:
        return 60 * int(minutes) + int(seconds)
    return 3600 * int(hours) + 60 * int(hour_minutes)


def format_peak(size: float) -> str:
    """A node's peak memory above its start: ``format_bytes``, but "< 1 MiB" below ``MEMORY_NOISE`` (never a
    negative size)."""
    return f"< {MEMORY_NOISE // 2**20} MiB" if size < MEMORY_NOISE else format_bytes(size)


def format_bytes(size: float) -> str:
    """A size in at most 8 characters: 12.3 MiB, 1.23 GiB."""
    if size < 1000 * 2**20:
        return f"{size / 2**20:.1f} MiB"
    return f"{size / 2**30:.2f} GiB"


def now() -> float:
    return time.perf_counter()


def _hidden_line(hidden: dict[str, list[NodeRecord]], shown_s: float, more: bool) -> str:
    """The closing table's line for the steps it does not list, counted as steps as its rows are: a step counts
    as ran if any of its variants ran; the variants, where a step has several, are counted apart in brackets."""
    records = [r for records in hidden.values() for r in records]
    took = format_duration(sum(r.seconds for r in records))
    status = Counter(_step_status(records) for records in hidden.values())
    how = ", ".join(f"{n} {s}" for s, n in status.items())
    variants = f"{len(records)} with their variants; " if len(records) > len(hidden) else ""
    steps = f"{len(hidden)} {'step' if len(hidden) == 1 else 'steps'}"
    lead = f"and {len(hidden)} more {steps.split()[1]}" if more else (f"all {steps}" if len(hidden) > 1 else steps)
    return f"{lead} under {shown_s:g} s each: {how} ({variants}{took} in all): {', '.join(hidden)}"


def _step_status(records: list[NodeRecord]) -> str:
    """One status for a step from its variants': the first of failed, ran, recomputed that one has, else cached."""
    found = {r.status for r in records}
    return next((s for s in ("failed", "ran", "recomputed") if s in found), "cached")


def bar_label(name: str, nodes: list[str]) -> str:
    """A run's progress bar title: what its count counts, the steps and, where a step has variants (each run
    apart, so the bar's total is larger), how many with them."""
    steps = len(set(nodes))
    return f"{name}: {steps} steps" + (f", {len(nodes)} with their variants" if len(nodes) > steps else "")
