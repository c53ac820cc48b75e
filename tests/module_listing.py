"""A script that runs ``nodegraph run ARGS`` in this process and prints the names of every module it imported: what a
cached re-run costs in imports (tests/engine/test_cached_rerun_imports.py, tests/placement/test_place_check.py)."""

RUN_AND_LIST = """
import runpy, sys
sys.argv = ["nodegraph", "run", *sys.argv[1:]]
try:
    runpy.run_module("nodegraph.cli", run_name="__main__")
except SystemExit as stop:
    assert not stop.code, stop.code
print(" ".join(sorted(sys.modules)))
"""
