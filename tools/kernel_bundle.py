"""Build or unpack a bundle of compiled kernels (``nodegraph/kernel_bundle.py``).

    python tools/kernel_bundle.py build [--out nodegraph/kernels.tar.gz] [--recipe graphs/ikura_don.yaml ...]
    python tools/kernel_bundle.py install BUNDLE      # into this installation's numba cache (a run does it itself)
    python tools/kernel_bundle.py check [BUNDLE]      # the entries whose module changed since the build

``build`` runs each recipe (by default every recipe in graphs/, so that a first run of any scene compiles nothing)
in a fresh process with an empty numba cache and an empty node cache (``--draft``:
a kernel's argument types do not depend on the size, and a draft compiles the same kernels sooner), kernels for
numba's ``generic`` CPU, then packs the cache files of the project's kernels. The
bundle is kept in git (``nodegraph/kernels.tar.gz``): rebuild it after a change to a kernel's module (``check``
names them; the suite fails on any).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def build(recipes: list[str], out: Path) -> int:
    from nodegraph import kernel_bundle

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        env = dict(os.environ, NUMBA_CACHE_DIR=str(work / "numba"), NUMBA_CPU_NAME=kernel_bundle.CPU)
        env[kernel_bundle.ENV_VAR] = "off"
        env.pop("NUMBA_CPU_FEATURES", None)
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
        for recipe in recipes:
            started = time.perf_counter()
            command = [sys.executable, "-m", "nodegraph.cli", "run", recipe, "--draft", "--no-rrd", "--quiet"]
            command += ["--cache-dir", str(work / "cache"), "--out-dir", str(work / "out")]
            subprocess.run(command, env=env, cwd=ROOT, check=True)
            print(f"{recipe}: {time.perf_counter() - started:.1f} s")
        os.environ["NUMBA_CACHE_DIR"] = env["NUMBA_CACHE_DIR"]
        count = kernel_bundle.pack(work / "numba", out)
    print(f"wrote {count} cache files into {out} ({out.stat().st_size / 1e6:.1f} MB)")
    return count


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    b = sub.add_parser("build")
    b.add_argument("--out", type=Path, default=None)
    b.add_argument("--recipe", action="append", default=None, help="default: every recipe in graphs/")
    i = sub.add_parser("install")
    i.add_argument("bundle", type=Path)
    c = sub.add_parser("check")
    c.add_argument("bundle", type=Path, nargs="?", default=None)
    args = ap.parse_args()
    from nodegraph import kernel_bundle, runtime

    if args.command == "build":
        every = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "graphs").glob("*.yaml"))
        build(args.recipe or every, args.out or kernel_bundle.BUNDLE)
    elif args.command == "check":
        old = kernel_bundle.stale(args.bundle or kernel_bundle.BUNDLE)
        print("\n".join(old) or "every entry matches the code")
        raise SystemExit(1 if old else 0)
    else:
        runtime.configure()
        written = kernel_bundle.install(args.bundle, Path(os.environ["NUMBA_CACHE_DIR"]))
        print(f"unpacked {written} cache files into {os.environ['NUMBA_CACHE_DIR']}")


if __name__ == "__main__":
    main()
