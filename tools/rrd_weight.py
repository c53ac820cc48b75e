"""How heavy a Rerun recording is and how long it takes to open: its size by entity (the chunk sizes
``rerun rrd print`` reports, summed per path prefix) and the seconds Rerun's own reader takes to decode and
index every chunk into a chunk store (what a viewer does on opening the file, without drawing it; the machine
has no display for the viewer itself), best of N; the seconds the viewer program itself takes to ingest the file
into its entity database and quit (``rerun --test-receive``, no window), best of N; and ``rerun rrd verify``'s.

    python tools/rrd_weight.py outputs/ikura_don/ikura_don.rrd [--depth 2] [--repeat 3]
"""

from __future__ import annotations

import argparse
import collections
import re
import subprocess
import sys
import time
from pathlib import Path

UNITS = {"B": 1, "KiB": 2**10, "MiB": 2**20, "GiB": 2**30}


def sizes_by_entity(path: Path, depth: int) -> collections.Counter:
    """Bytes (uncompressed chunk sizes) per entity path cut to ``depth`` levels."""
    printed = subprocess.run(["rerun", "rrd", "print", str(path)], capture_output=True, text=True, check=True).stdout
    sizes: collections.Counter = collections.Counter()
    for match in re.finditer(r"with \d+ rows \(([\d.]+) (B|KiB|MiB|GiB)\) - (\S+)", printed):
        key = "/".join(match.group(3).split("/")[: depth + 1])
        sizes[key] += float(match.group(1)) * UNITS[match.group(2)]
    return sizes


def open_seconds(path: Path, repeat: int) -> tuple[float, int]:
    """Best-of-``repeat`` seconds to read every chunk of ``path`` into a chunk store, and the chunk count."""
    from rerun.chunk import RrdReader

    best, chunks = float("inf"), 0
    for _ in range(repeat):
        start = time.perf_counter()
        store = RrdReader(str(path)).stream().collect()
        chunks = sum(1 for _ in store.stream())
        best = min(best, time.perf_counter() - start)
    return best, chunks


def viewer_seconds(path: Path, repeat: int) -> float:
    """Best-of-``repeat`` wall seconds of ``rerun --test-receive FILE``: the viewer program started, the file
    ingested into its entity database, then quit (no window drawn; its gRPC port is an unusual one)."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        command = ["rerun", "--test-receive", "--port", "19871", str(path)]
        subprocess.run(command, capture_output=True, check=True, timeout=300)
        best = min(best, time.perf_counter() - start)
    return best


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rrd", type=Path)
    parser.add_argument("--depth", type=int, default=2, help="entity path levels to sum by (default 2)")
    parser.add_argument("--repeat", type=int, default=3, help="loads timed, the best kept (default 3)")
    parser.add_argument("--top", type=int, default=12, help="heaviest entities shown (default 12)")
    args = parser.parse_args(argv)
    sizes = sizes_by_entity(args.rrd, args.depth)
    seconds, chunks = open_seconds(args.rrd, args.repeat)
    viewer = viewer_seconds(args.rrd, args.repeat)
    start = time.perf_counter()
    verify = subprocess.run(["rerun", "rrd", "verify", str(args.rrd)], capture_output=True, text=True)
    verified = time.perf_counter() - start
    print(
        f"{args.rrd}: {args.rrd.stat().st_size / 1e6:.1f} MB on disk, {sum(sizes.values()) / 2**20:.1f} MiB of chunks, "
        f"{chunks} chunks; read into a chunk store in {seconds:.2f} s, ingested by the viewer (rerun --test-receive) "
        f"in {viewer:.2f} s (best of {args.repeat}); rerun rrd verify "
        f"{verified:.2f} s ({'ok' if verify.returncode == 0 else 'FAILED'})"
    )
    for entity, size in sizes.most_common(args.top):
        print(f"  {size / 2**20:8.2f} MiB  {entity}")
    return 0 if verify.returncode == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
