"""Whatever bytes or structure a recipe holds, `nodegraph check` answers with exit 2 and a located
message, never a traceback, within bounded memory; a damaged numba cache says how to recover."""

import os
import resource
import subprocess
import sys
from pathlib import Path

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nodegraph.cli import main

SCALARS = st.one_of(
    st.none(), st.booleans(), st.integers(-(10**12), 10**12), st.floats(allow_nan=True), st.text(max_size=12)
)
KEYS = st.sampled_from(
    [
        "name",
        "seed",
        "effects",
        "outputs",
        "nodes",
        "type",
        "params",
        "inputs",
        "variants",
        "base_mesh",
        "voxelise",
        "mesh",
        "b",
        "b.mesh",
        "count",
        "resolution",
    ]
) | st.text(max_size=6)
STRUCTURES = st.recursive(
    SCALARS, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(KEYS, inner, max_size=5), max_leaves=30
)


def check(tmp_path: Path, data: bytes, capsys) -> tuple[int, str]:
    path = tmp_path / "fuzz.yaml"
    path.write_bytes(data)
    code = main(["check", str(path)])
    return code, capsys.readouterr().err


def assert_located(code: int, err: str) -> None:
    assert code in (0, 2), err
    if code == 2:
        assert "fuzz.yaml:" in err or "--set" in err, err
        assert "Traceback" not in err


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.binary(max_size=300))
def test_random_bytes(tmp_path, capsys, data):
    assert_located(*check(tmp_path, data, capsys))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(STRUCTURES)
def test_random_structures(tmp_path, capsys, value):
    assert_located(*check(tmp_path, yaml.safe_dump(value).encode(), capsys))


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.dictionaries(st.sampled_from(["a", "b", "v"]), st.dictionaries(KEYS, STRUCTURES, max_size=4), max_size=3))
def test_random_nodes_in_a_valid_frame(tmp_path, capsys, nodes):
    text = yaml.safe_dump({"outputs": ["b"], "effects": [], "nodes": nodes})
    assert_located(*check(tmp_path, text.encode(), capsys))


def test_an_alias_bomb_is_refused_within_bounded_memory(tmp_path):
    lines = ["a: &a [" + ", ".join(['"lol"'] * 9) + "]"]
    for i in range(1, 12):
        lines.append(f"l{i}: &l{i} [" + ", ".join([f"*{'a' if i == 1 else f'l{i - 1}'}"] * 9) + "]")
    (tmp_path / "bomb.yaml").write_text("\n".join(lines) + "\n")
    probe = (
        "import resource, sys; from nodegraph.cli import main; code = main(['check', sys.argv[1]]); "
        "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr); sys.exit(code)"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe, str(tmp_path / "bomb.yaml")], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 2 and "expands to more than" in done.stderr and "bomb.yaml:" in done.stderr
    peak_kib = int(done.stderr.strip().splitlines()[-1])
    baseline = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    assert peak_kib < max(600_000, 2 * baseline)  # 9^12 values were never built


def test_a_damaged_numba_cache_names_the_fix(tmp_path):
    recipe = tmp_path / "v.yaml"
    recipe.write_text(
        "outputs: [v]\nnodes:\n  b: {type: base_mesh}\n"
        "  v: {type: voxelise, inputs: {mesh: b.mesh}, params: {resolution: 16}}\n"
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    cmd = [
        sys.executable,
        "-m",
        "nodegraph.cli",
        "run",
        str(recipe),
        "--no-cache",
        "--no-rrd",
        "-q",
        "--out-dir",
        str(tmp_path / "out"),
    ]
    subprocess.run(cmd, env=env, check=True, capture_output=True, timeout=300)
    damaged = list((tmp_path / "numba").rglob("*.nbc"))
    assert damaged
    for path in damaged:
        path.write_bytes(path.read_bytes()[:20])
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 1
    assert "compiled-kernel cache looks damaged" in done.stderr and str(tmp_path / "numba") in done.stderr


NODE_TYPES = st.sampled_from(["base_mesh", "sphere_scatter", "voxelise", "shape", "poisson_place", "xpbd", "shade"])
PARAM_NAMES = st.sampled_from(
    ["count", "resolution", "size", "kind", "r", "frames", "mode", "path", "variety", "water_content", "seed"]
) | st.text(max_size=5)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(NODE_TYPES, st.dictionaries(PARAM_NAMES, STRUCTURES, max_size=4), STRUCTURES, STRUCTURES)
def test_real_node_types_with_random_parameters_and_wires(tmp_path, capsys, node_type, params, inputs, variants):
    nodes = {"b": {"type": "base_mesh"}, "n": {"type": node_type, "params": params, "inputs": inputs}}
    if variants is not None:
        nodes["n"]["variants"] = variants
    text = yaml.safe_dump({"outputs": ["n"], "nodes": nodes})
    assert_located(*check(tmp_path, text.encode(), capsys))
