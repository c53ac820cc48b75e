import time
from pathlib import Path

import pytest

from nodegraph.cache import Cache
from nodegraph.registry import Registry

TOY = Path(__file__).with_name("toy_nodes.py")


@pytest.fixture(scope="session")
def registry():
    reg = Registry()
    reg.add_plugin_file(TOY)
    return reg


@pytest.fixture
def cache(tmp_path):
    return Cache(tmp_path / "cache")


@pytest.fixture
def recipe_file(tmp_path):
    def write(text, name="recipe.yaml"):
        path = tmp_path / name
        path.write_text(text)
        return path

    return write


@pytest.fixture
def node_started():
    """``wait(folder, proc)``: block until a ``toy_slow`` node has written its file in ``folder`` (from then on
    it is running: a signal sent now lands inside the node, however loaded the machine) and return the id of
    the process running it; fails at once if ``proc`` ends first."""

    def wait(folder: Path, proc=None, timeout: float = 120.0) -> int:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            found = sorted(folder.glob("*")) if folder.is_dir() else []
            if found:
                return int(found[0].name)
            if proc is not None and proc.poll() is not None:
                pytest.fail(f"the run ended (exit status {proc.returncode}) before its slow node started")
            time.sleep(0.02)
        pytest.fail(f"no slow node started within {timeout} s")

    return wait
