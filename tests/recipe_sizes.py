"""The reduced recipe sizes shared by the benchmark and the tests that run recipes small."""

from pathlib import Path


def quick_sizes() -> dict[str, list[str]]:
    """``benchmarks/bench_scenes.py``'s reduced sizes (each recipe's ``draft:`` block with a smaller preview), one
    list of ``--set`` overrides per recipe, shared by the benchmark and the tests that run recipes small."""
    import importlib.util

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_scenes.py"
    spec = importlib.util.spec_from_file_location("bench_scenes_sizes", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.QUICK
