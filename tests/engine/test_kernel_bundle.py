"""Shipped kernels (``nodegraph.kernel_bundle``): a bundle packs numba's cache files by source folder and unpacks
them where another installation's locator looks, so that a first run loads its kernels instead of compiling."""

import json
import os
import subprocess
import sys

from nodegraph import kernel_bundle


def _entry(cache, root, folder, name, data):
    path = cache / kernel_bundle._cache_subpath(root / folder) / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)
    return path


def test_a_bundle_unpacks_where_another_installation_looks_and_keeps_what_is_there(tmp_path, monkeypatch):
    """Packed from one checkout, unpacked for a checkout elsewhere: each file lands in the folder numba's locator
    names for the other checkout's source folder (numba names it by the absolute path). A file there already is
    kept; a folder that is no project source folder is not packed; a bundle for another numba is not unpacked."""
    here = kernel_bundle.project_roots()
    cache = tmp_path / "built"
    _entry(cache, here["nodes"], "simulation", "integrate.predict-1.py311.nbi", b"index")
    _entry(cache, here["nodes"], "simulation", "integrate.predict-1.py311.0.nbc", b"code")
    (cache / "elsewhere_0123").mkdir()
    (cache / "elsewhere_0123" / "f-1.py311.nbi").write_bytes(b"foreign")
    bundle = tmp_path / "kernels.tar.gz"
    assert kernel_bundle.pack(cache, bundle) == 2

    other = {name: tmp_path / "checkout" / name for name in here}
    monkeypatch.setattr(kernel_bundle, "project_roots", lambda: other)
    target = tmp_path / "fresh"
    kept = _entry(target, other["nodes"], "simulation", "integrate.predict-1.py311.0.nbc", b"mine")
    assert kernel_bundle.install(bundle, target) == 1
    unpacked = target / kernel_bundle._cache_subpath(other["nodes"] / "simulation") / "integrate.predict-1.py311.nbi"
    assert unpacked.read_bytes() == b"index"
    assert kept.read_bytes() == b"mine"
    assert not (target / "elsewhere_0123").exists()

    monkeypatch.setattr(kernel_bundle, "manifest", lambda: {"numba": "0.0", "python": "3.11", "cpu": "generic"})
    assert kernel_bundle.install(bundle, tmp_path / "other-numba") == 0


def test_each_installation_sharing_a_cache_unpacks_the_bundle_once(tmp_path, monkeypatch):
    """A run unpacks the bundle once per bundle file and installation: the next run finds its marker and reads
    nothing; a second checkout using the same cache folder gets its own copy (numba's folders name the source
    folder's absolute path)."""
    here = kernel_bundle.project_roots()
    _entry(tmp_path / "built", here["nodes"], "simulation", "integrate.predict-1.py311.nbi", b"index")
    bundle = tmp_path / "kernels.tar.gz"
    kernel_bundle.pack(tmp_path / "built", bundle)
    monkeypatch.setenv(kernel_bundle.ENV_VAR, str(bundle))
    monkeypatch.setenv("NUMBA_CPU_NAME", kernel_bundle.CPU)
    shared = tmp_path / "shared"
    assert kernel_bundle.ensure_installed(shared) == 1
    assert kernel_bundle.ensure_installed(shared) == 0
    other = {name: tmp_path / "checkout" / name for name in here}
    monkeypatch.setattr(kernel_bundle, "project_roots", lambda: other)
    assert kernel_bundle.ensure_installed(shared) == 1
    monkeypatch.setenv(kernel_bundle.ENV_VAR, "off")
    assert kernel_bundle.ensure_installed(tmp_path / "off") == 0


# Runs in a fresh process: one project kernel from numba's cache (or compiled), and numba's count of each.
PROBE = """
import json, sys
import numpy as np
from nodegraph import runtime
runtime.configure()
from nodes.simulation.integrate import kinetic_energy
kinetic_energy(np.ones((3, 3)), np.ones(3))
stats = kinetic_energy.stats
print(json.dumps([sum(stats.cache_hits.values()), sum(stats.cache_misses.values())]))
"""


def test_a_first_run_loads_the_shipped_kernels_instead_of_compiling(tmp_path):
    """An empty numba cache and a bundle: the kernel loads (a cache hit), no compilation; without the bundle
    (``NODEGRAPH_KERNEL_BUNDLE=off``) an empty cache compiles it (a miss)."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES")}
    env["PYTHONPATH"] = os.pathsep.join(sys.path)

    def run(cache, bundle):
        env.update(NUMBA_CACHE_DIR=str(tmp_path / cache), NODEGRAPH_KERNEL_BUNDLE=bundle)
        done = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env)
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout.splitlines()[-1])

    assert run("built", "off") == [0, 1]
    bundle = tmp_path / "kernels.tar.gz"
    assert kernel_bundle.pack(tmp_path / "built", bundle) == 2  # the index and the machine code
    assert run("fresh", str(bundle)) == [1, 0]


def _index(stamp) -> bytes:
    """An index file as numba writes one: its version pickled, then the pickled ``(stamp, overloads)``."""
    import pickle

    return pickle.dumps("0.68.1") + pickle.dumps((stamp, {}))


def test_stale_names_the_entries_whose_module_changed_since_the_build(tmp_path):
    """An index stamped with its module's current code digest is fresh; one stamped with another digest (its module
    edited after the build) is named, so that the bundle is rebuilt rather than silently compiling on a first run."""
    from nodegraph import code_digest
    from nodegraph.node_packages import project_packages

    here = kernel_bundle.project_roots()
    digest = code_digest.module_digest("nodes.simulation.integrate", project_packages())
    cache = tmp_path / "built"
    _entry(cache, here["nodes"], "simulation", "integrate.predict-1.py311.nbi", _index(digest))
    _entry(cache, here["nodes"], "simulation", "integrate.predict-1.py311.0.nbc", b"code")
    _entry(cache, here["nodes"], "simulation", "integrate.other-9.py311.nbi", _index("an older digest"))
    bundle = tmp_path / "kernels.tar.gz"
    kernel_bundle.pack(cache, bundle)
    assert kernel_bundle.stale(bundle) == ["nodes/simulation/integrate.other-9.py311.nbi"]


def test_the_shipped_bundle_matches_the_code():
    """The bundle kept in git holds an entry for the kernels of the main job and every entry matches the code, so a
    first run from a checkout compiles nothing (rebuild: ``python tools/kernel_bundle.py build``, ≈ 100 CPU s)."""
    import pytest

    bundle = kernel_bundle.BUNDLE
    assert bundle.is_file(), "nodegraph/kernels.tar.gz is missing: python tools/kernel_bundle.py build"
    if not kernel_bundle.fits(bundle):
        pytest.skip(f"the bundle is for {kernel_bundle.manifest()} only where it was built")
    old = kernel_bundle.stale(bundle)
    assert not old, f"rebuild the bundle (python tools/kernel_bundle.py build): {len(old)} stale, e.g. {old[:3]}"


def test_the_estimate_says_no_kernel_is_due_where_the_shipped_bundle_holds_them(tmp_path, monkeypatch):
    """A clean clone's first run loads the shipped kernels, so its estimate must not say they are compiled first (a new
    user was told "its kernels are not compiled yet" by a run that compiled none); without the bundle it says so."""
    from pathlib import Path

    from nodegraph import compile_ahead
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))  # no run has marked anything here
    recipe = load_recipe(Path(__file__).resolve().parents[2] / "graphs" / "ikura_don.yaml", default_registry())
    monkeypatch.setenv(kernel_bundle.ENV_VAR, "off")
    assert compile_ahead.kernels_due(recipe)
    monkeypatch.setenv(kernel_bundle.ENV_VAR, str(kernel_bundle.BUNDLE))
    assert not compile_ahead.kernels_due(recipe)
