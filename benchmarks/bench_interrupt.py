"""How long a run takes to exit after Ctrl-C or SIGTERM, and whether anything is left running.

``--quick``: one SIGINT 1.5 s into ``rice_bowl.yaml --draft`` (CI's smoke run). ``random``: start ``nodegraph run
RECIPE --no-cache`` in a process group of its own, wait a random 1–20 s (seeded),
send SIGINT to the group (what Ctrl-C at a terminal does), and time the exit; repeated ``--tries`` times.
``steps``: for each of ``--steps`` (``all``: every node of the recipe; ``types``: the first node of each type) and
each of SIGINT and SIGTERM, remove that step and every step after it from the cache ``--cache-dir`` (warmed by a
first, complete run), run, and signal ``--delay`` s after the step has started (read from the run's listing of its
running steps, ``interrupt.RUNNING``, written as the step starts); ``--alternate``: one signal a step, SIGINT and
SIGTERM in turn; ``--assert-s``: exit with an error where any run took longer to exit or left a process running. A
run not gone ``HANG_S`` after the signal is a hang: every process of the group prints its threads' stacks (``kill
-USR1``: faulthandler, registered by the command) before it is killed. One JSON line per try on stdout: the step(s)
running (from the run's 'interrupted' line), the seconds to exit, the exit status, the processes left.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from nodegraph.interrupt import RUNNING

SAID_LINE = re.compile(r"\binterrupted( during|\.| before|:)")  # the run's own stop line, or its supervisor's
HANG_S = 30.0  # seconds after the signal before a run still there counts as hung


def group_pids(pgid: int) -> list[int]:
    """The live processes of a process group (from /proc)."""
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[2]) == pgid and fields[0] != "Z":
                pids.append(int(entry.name))
    return pids


def started(listings: Path, step: str) -> bool:
    """Whether the run's listing (``interrupt.supervise``'s, in the run's own temporary folder) shows ``step``, or
    one of its instances (``step[3]``), started."""
    for listing in listings.glob("nodegraph-leftovers-*.txt"):
        for line in listing.read_text(errors="replace").splitlines():
            label = line.removeprefix(RUNNING).partition("\t")[0]
            if line.startswith(RUNNING) and (label == step or label.startswith(step + "[")):
                return True
    return False


def one(command: list[str], signum: int, after: float | None, step: str | None, delay: float = 1.0) -> dict:
    """Run ``command``; signal it ``after`` seconds in, or ``delay`` s after ``step`` has started; time the exit."""
    with tempfile.TemporaryDirectory(
        prefix="bench-interrupt-tmp-", ignore_cleanup_errors=True
    ) as listings:  # the run's TMPDIR: its listing
        return _signalled(command, signum, after, step, delay, Path(listings))


def _signalled(command: list[str], signum: int, after: float | None, step: str | None, delay: float, listings: Path):
    """``one`` with the run's TMPDIR ``listings``."""
    log = tempfile.NamedTemporaryFile("w+b", suffix=".log", delete=False)
    env = dict(os.environ, NODEGRAPH_HEARTBEAT="0.2", TMPDIR=str(listings))
    proc = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, start_new_session=True, env=env)
    start = time.monotonic()
    ended = None
    while proc.poll() is None:
        if ended is None and step is not None and started(listings, step):
            ended = time.monotonic()
        if (after is not None and time.monotonic() - start >= after) or (
            ended is not None and time.monotonic() - ended >= delay
        ):
            break
        time.sleep(0.01)
    if proc.poll() is not None:
        os.unlink(log.name)
        return {"signal": None, "ended_by_itself_s": round(time.monotonic() - start, 1)}
    signalled = time.monotonic()
    os.killpg(proc.pid, signum)
    try:
        proc.wait(timeout=HANG_S)
        hang = None
    except subprocess.TimeoutExpired:
        for pid in group_pids(proc.pid):
            os.kill(pid, signal.SIGUSR1)
        time.sleep(1.0)
        hang = Path(log.name).read_text(errors="replace")[-8000:]
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    exit_s = time.monotonic() - signalled
    time.sleep(0.2)
    left = group_pids(proc.pid)
    lines = Path(log.name).read_text(errors="replace").splitlines()
    # the line may follow another process's unfinished output on the same line of the log (stdout and stderr share it)
    said = [line[m.start() :] for line in lines if (m := SAID_LINE.search(line))]
    # "interrupted during rice_sim (12 s in), egg_sim (3 s in). Kept: …": the step(s) running
    during = said[-1].partition(" during ")[2].partition(". ")[0] if said else None
    running = re.sub(r" \(\d+ s in\)", "", during) if during is not None else None
    tail = None if said and proc.returncode == 130 else lines[-6:]  # what an unexpected ending printed last
    os.unlink(log.name)
    return {
        "signal": signal.Signals(signum).name,
        "at_s": round(signalled - start, 1),
        "running": running,
        "exit_s": round(exit_s, 2),
        "status": proc.returncode,
        "left": left,
        "hang": hang,
        "said": said,
        "tail": tail,
    }


def forget(cache: Path, recipe: str, step: str, draft: bool) -> dict[Path, bytes]:
    """Remove ``step`` and every step that depends on it from ``cache``, and any saved progress: the next run
    computes them (and only them). Returns the entries removed (path: bytes), for ``restore``."""
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    loaded = load_recipe(Path(recipe), default_registry(), draft=draft)
    after = {n for n in loaded.nodes if step in loaded.graph.ancestors(n)} | {step}
    removed = {}
    for entry in (cache / "entries").glob("*/*.json"):
        data = entry.read_bytes()
        if json.loads(data).get("node") in after:
            removed[entry] = data
            entry.unlink()
    for saved in (cache / "checkpoints").glob("*"):
        saved.unlink()
    return removed


def restore(removed: dict[Path, bytes]) -> None:
    """Put back the entries ``forget`` removed (their blobs stay in the cache): the next step's run finds what
    precedes it cached, not computed again because this try stopped it."""
    for entry, data in removed.items():
        if not entry.exists():
            entry.write_bytes(data)


def every_step(recipe: str, draft: bool, one_per_type: bool = False) -> list[str]:
    """The recipe's nodes in the order a run computes them; ``one_per_type``: the first of each node type only (two
    steps of one type run the same code, so they stop alike)."""
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    loaded = load_recipe(Path(recipe), default_registry(), draft=draft)
    order = list(loaded.graph.topological_order())
    if not one_per_type:
        return order
    first = {}
    for step in order:
        first.setdefault(loaded.nodes[step].spec.type_name, step)
    return [step for step in order if step in first.values()]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mode", nargs="?", choices=["random", "steps"], default="random")
    parser.add_argument("recipe", nargs="?", default=str(Path(__file__).resolve().parents[1] / "graphs/rice_bowl.yaml"))
    parser.add_argument("--quick", action="store_true", help="one SIGINT 1.5 s into a draft run: seconds, for CI")
    parser.add_argument("--tries", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--steps",
        default="",
        help="steps mode: comma-separated step (node) names, all, or types (the first step of each node type)",
    )
    parser.add_argument("--delay", type=float, default=1.0, help="steps mode: seconds after the step started")
    parser.add_argument("--cache-dir", type=Path, default=None, help="steps mode: a cache the recipe's run filled")
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--draft", action="store_true")
    parser.add_argument("--rrd", action="store_true", help="steps mode: with the run's recording, as a user's run")
    parser.add_argument("--alternate", action="store_true", help="steps mode: one signal a step, INT and TERM in turn")
    parser.add_argument("--assert-s", type=float, default=None, help="exit 1 where a run took longer to exit")
    args = parser.parse_args()
    if args.quick:
        args.mode, args.tries, args.draft = "random", 1, True
    with tempfile.TemporaryDirectory(prefix="bench-interrupt-", ignore_cleanup_errors=True) as out:
        measure(args, out)


def measure(args, out: str) -> None:
    """Each try's row, printed as one JSON line; exits 1 where ``--assert-s`` is broken. ``out``: the runs' folder."""
    command = [sys.executable, "-m", "nodegraph.cli", "run", args.recipe, "--out-dir", out]
    command += [] if args.rrd and args.mode == "steps" else ["--no-rrd"]
    command += ["--no-cache"] if args.mode == "random" else ["--cache-dir", str(args.cache_dir)]
    command += ["--draft"] * args.draft + [x for o in args.overrides for x in ("--set", o)]
    if args.mode == "random":
        rng = random.Random(args.seed)
        for _ in range(args.tries):
            tried = one(command, signal.SIGINT, 1.5 if args.quick else rng.uniform(1.0, 20.0), None)
            print(json.dumps(tried), flush=True)
            if args.quick and (tried["hang"] or tried["left"]):
                sys.exit("the run did not stop cleanly")
    else:
        slow = []
        named = args.steps.split(",")
        steps = every_step(args.recipe, args.draft, args.steps == "types") if args.steps in ("all", "types") else named
        for k, step in enumerate(steps):
            both = (signal.SIGINT, signal.SIGTERM)
            for signum in both[k % 2 :][:1] if args.alternate else both:
                removed = forget(args.cache_dir, args.recipe, step, args.draft)
                tried = {"step": step, **one(command, signum, None, step, args.delay)}
                restore(removed)
                print(json.dumps(tried), flush=True)
                if args.assert_s is not None and (tried.get("exit_s", 0.0) > args.assert_s or tried.get("left")):
                    slow.append(f"{step} {tried['signal']}: {tried['exit_s']} s, left {tried['left']}")
        if slow:
            sys.exit(f"over {args.assert_s} s or left running: " + "; ".join(slow))


if __name__ == "__main__":
    main()
