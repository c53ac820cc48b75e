"""A cached re-run's recording is the cold run's, from the Rerun fragments kept with the cache entries:
same entities, timelines and component values (``rerun rrd compare``), without logging values again."""

import json
import subprocess
import sys
from pathlib import Path

from rerun.chunk import RrdReader

from nodegraph.cli import main

TOY = str(Path(__file__).with_name("toy_nodes.py"))
# slow and slow_twin are the same computation (one cache key), logged at two entity paths
RECIPE = """\
name: replay
seed: 2
outputs: [surf, twin]
nodes:
  pts: {type: toy_points, variants: 2, params: {count: 6}}
  merge: {type: toy_merge, inputs: {parts: pts.spheres}}
  slow: {type: toy_slow, inputs: {spheres: merge.spheres}}
  slow_twin: {type: toy_slow, inputs: {spheres: merge.spheres}}
  surf: {type: toy_sphere_mesh, inputs: {spheres: slow.spheres}}
  twin: {type: toy_sphere_mesh, inputs: {spheres: slow_twin.spheres}}
"""


def run(tmp_path, *extra, quiet=True) -> int:
    flags = ["-q"] if quiet else []
    return main(["run", "replay.yaml", "--plugin", TOY, "--cache-dir", str(tmp_path / "cache"), *flags, *extra])


def compare(a: Path, b: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "compare", "--unordered", str(a), str(b)], capture_output=True, text=True
    )


def entities(path: Path) -> set[str]:
    return set(RrdReader(str(path)).stream().collect().schema().entity_paths())


def energy_steps(path: Path, entity: str) -> list[int]:
    import datafusion

    ctx = datafusion.SessionContext()
    store = RrdReader(str(path)).stream().collect()
    return store.reader("sim_step", contents=entity, ctx=ctx).to_arrow_table().column("sim_step").to_pylist()


def fragments(tmp_path) -> dict[str, dict]:
    out = {}
    for entry in (tmp_path / "cache" / "entries").glob("*/*.json"):
        manifest = json.loads(entry.read_text())
        out[manifest["node"]] = manifest.get("rerun")
    return out


def test_a_cached_rerun_replays_the_cold_runs_logs_identically(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "replay.yaml").write_text(RECIPE)
    assert run(tmp_path, "--rrd", "cold.rrd") == 0
    capsys.readouterr()
    assert run(tmp_path, "--rrd", "cached.rrd", quiet=False) == 0
    err = capsys.readouterr().err  # every instance of the second run came from the cache
    assert "cached" in err and "ran" not in err.replace("nodegraph run", "")
    assert run(tmp_path, "--rrd", "again.rrd") == 0
    done = compare(tmp_path / "cold.rrd", tmp_path / "cached.rrd")
    assert done.returncode == 0, done.stderr[-3000:]
    assert compare(tmp_path / "cached.rrd", tmp_path / "again.rrd").returncode == 0
    # what the nodes logged as they ran is there on a cached run too (it was lost before fragments)
    names = entities(tmp_path / "cached.rrd")
    assert {"/slow/log/energy", "/slow_twin/log/energy", "/pts/0/spheres", "/pts/1/spheres", "/surf/mesh"} <= names
    assert energy_steps(tmp_path / "cached.rrd", "/slow/log/energy") == list(range(10))
    assert energy_steps(tmp_path / "cached.rrd", "/slow_twin/log/energy") == list(range(10))
    kept = fragments(tmp_path)
    assert set(kept) == {"pts", "merge", "slow_twin", "twin"} and all(kept.values())  # one entry per key
    # surf's logs come from the entry twin stored (same key): moved to /surf on the way in
    assert kept["twin"]["entity"] == "/twin" and kept["twin"]["logged"] == {"/mesh": ["Mesh3D"]}
    leftovers = [p.name for p in (tmp_path / "cache").rglob("*") if p.suffix == ".tmp"]
    assert not leftovers, leftovers


def test_a_different_setting_differs_so_the_comparison_can_fail(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "replay.yaml").write_text(RECIPE)
    assert run(tmp_path, "--rrd", "a.rrd") == 0
    assert run(tmp_path, "--rrd", "b.rrd", "--set", "pts.count=7") == 0
    assert compare(tmp_path / "a.rrd", tmp_path / "b.rrd").returncode != 0


def test_entries_without_fragments_get_them_and_a_damaged_one_is_logged_again(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "replay.yaml").write_text(RECIPE)
    assert run(tmp_path, "--no-rrd") == 0  # entries without fragments (as a worker leaves them)
    assert not any(fragments(tmp_path).values())
    assert run(tmp_path, "--rrd", "first.rrd") == 0  # outputs logged from the values, fragments kept
    kept = fragments(tmp_path)
    assert all(kept.values()), kept
    surf = next((tmp_path / "cache" / "rerun").glob(f"*/{_key_of(tmp_path, 'twin')}.rrd"))
    surf.write_bytes(surf.read_bytes()[:-100])  # truncated
    capsys.readouterr()
    assert run(tmp_path, "--rrd", "second.rrd", quiet=False) == 0
    assert "does not match its entry" in " ".join(capsys.readouterr().err.split())
    done = compare(tmp_path / "first.rrd", tmp_path / "second.rrd")
    assert done.returncode == 0, done.stderr[-3000:]
    assert "/surf/mesh" in entities(tmp_path / "second.rrd")


def _key_of(tmp_path, node: str) -> str:
    for entry in (tmp_path / "cache" / "entries").glob("*/*.json"):
        manifest = json.loads(entry.read_text())
        if manifest["node"] == node:
            return manifest["key"]
    raise AssertionError(f"no entry for {node}")


def test_inspect_prints_entities_timelines_and_blueprint_views(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "replay.yaml").write_text(RECIPE.replace("variants: 2", "variants: 3"))
    assert run(tmp_path, "--rrd", "r.rrd") == 0
    capsys.readouterr()
    assert main(["inspect", "r.rrd", "--depth", "3"]) == 0
    text = capsys.readouterr().out
    rid = RrdReader("r.rrd").recordings()[0].recording_id
    assert f"recording {rid} (nodegraph): replay" in text
    assert "timelines: row 0…2, sim_step 0…9" in text
    assert "0…2 (3 alike; the first shown)" in text  # pts/0, pts/1, pts/2 folded
    assert "\n  slow\n    log\n      energy  [Scalars]\n" in text  # /slow/log/energy: 3 levels
    assert "slow: energy [TimeSeries] origin /: + /slow/log/energy" in text
    assert "final scene (twin) [3D]" in text and "replay [tabs]" in text
    assert main(["inspect", "missing.rrd"]) == 2
    assert "missing.rrd: no such file" in capsys.readouterr().err


def test_a_failed_nodes_logs_go_to_the_partial_recording_only(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "replay.yaml").write_text(RECIPE)
    assert run(tmp_path, "--rrd", "r.rrd") == 0
    complete = (tmp_path / "r.rrd").read_bytes()
    (tmp_path / "replay.yaml").write_text(RECIPE.replace("slow_twin: {type: toy_slow", "slow_twin: {type: toy_fail"))
    assert run(tmp_path, "--rrd", "r.rrd") == 1
    assert (tmp_path / "r.rrd").read_bytes() == complete
    (partial,) = tmp_path.glob("r.*.partial.rrd")  # the failed run's own (NAME.<pid>.partial.rrd)
    assert energy_steps(partial, "/slow_twin/log/energy") == [0, 1]  # what it logged before it failed
    assert "/slow/spheres" in entities(partial)  # and the nodes before it
    assert not [p.name for p in tmp_path.rglob("*") if p.suffix == ".tmp" or p.name.startswith("nodegraph-")]


def test_a_capture_started_in_a_new_cache_leaves_it_clearable(tmp_path):
    from nodegraph.cache import Cache

    cache = Cache(tmp_path / "fresh")
    cache.capture_path("ab" * 32)  # a run interrupted in its first node leaves only this behind
    assert cache.is_cache()
    cache.clear()
    assert not (tmp_path / "fresh").exists()


def test_an_aggregate_is_logged_by_instancing_and_draws_its_elements_where_they_are(tmp_path):
    """Each library mesh once with a pose per element (Rerun's InstancePoses3D, mat3x3 read back column-major
    as Rerun stores it): the posed vertices are the aggregate's world-space vertices, element by element."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    from nodegraph.rerun_log import RunRecording, log_value
    from nodegraph.values import Mesh
    from nodes.simulation.aggregate import DeformedAggregate
    from nodes.values import Aggregate, ElementLibrary, Placement

    rng = np.random.default_rng(4)
    tetra = Mesh([[0, 0, 0], [2, 0, 0], [0, 1, 0], [0, 0, 0.5]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    stick = Mesh([[0, 0, 0], [3, 0, 0], [0, 0.2, 0]], [[0, 1, 2]])
    libraries = (ElementLibrary("grain", (tetra, stick)), ElementLibrary("egg", (stick,)))
    n = 12
    placement = Placement(
        rng.normal(size=(n, 3)) * 5,
        np.tile([0.0, 0.0, 1.0], (n, 1)),
        Rotation.random(n, random_state=3).as_matrix(),
        kinds=rng.integers(0, 2, n),
        variants=rng.integers(0, 5, n),
    )
    deformations = np.eye(3) + 0.2 * rng.normal(size=(n, 3, 3))
    # an egg: a shell and an inner part (parts == 1) that the solver moved by its own offset per element
    egg = Mesh(
        np.concatenate([tetra.vertices, tetra.vertices * 0.3 + 0.1]),
        np.concatenate([tetra.faces, tetra.faces + 4]),
        parts=np.repeat([0, 1], 4),
    )
    eggs = (ElementLibrary("grain", (tetra, stick)), ElementLibrary("egg", (egg,)))
    offsets = rng.normal(size=(n, 3)) * 0.1
    for aggregate, names in (
        (Aggregate(placement, libraries), {"grain/000", "grain/001", "egg/000"}),
        (Aggregate(placement, libraries, deformations), {"grain/000", "grain/001", "egg/000"}),
        (
            DeformedAggregate(placement, eggs, deformations, part_offsets=offsets),
            {"grain/000", "grain/001", "egg/000/rest", "egg/000/part1"},
        ),
    ):
        recording = RunRecording(tmp_path / "a.rrd", "agg")
        log_value(aggregate, recording.logger("/agg"))
        recording.close()
        drawn = []
        store = RrdReader(str(tmp_path / "a.rrd")).stream().collect()
        by_path: dict[str, dict] = {}
        for chunk in store.stream():
            batch = chunk.to_record_batch()
            for column in batch.schema.names:
                if ":" in column:
                    by_path.setdefault(chunk.entity_path, {})[column] = batch.column(column).to_pylist()[0]
        meshes = {p: f for p, f in by_path.items() if p.startswith("/agg/")}
        assert set(meshes) == {f"/agg/elements/{name}" for name in names}
        for fields in meshes.values():
            vertices = np.asarray(fields["Mesh3D:vertex_positions"], np.float64).reshape(-1, 3)
            moves = np.asarray(fields["InstancePoses3D:translations"], np.float64).reshape(-1, 3)
            flat = np.asarray(fields["InstancePoses3D:mat3x3"], np.float64).reshape(-1, 9)
            for t, columns in zip(moves, flat):
                matrix = columns.reshape(3, 3).T  # flat_columns: column j is columns[3j:3j+3]
                drawn.append(vertices @ matrix.T + t)
        expected = aggregate.combined_mesh().vertices
        drawn = np.concatenate(drawn)
        assert len(drawn) == len(expected)
        rows = np.round(drawn, 3), np.round(expected, 3)  # rows in one order, float32 noise rounded off
        rows = [r[np.lexsort(r.T[::-1])] for r in rows]
        assert np.allclose(rows[0], rows[1], atol=2e-3)


def test_a_fragment_logged_by_other_loggers_is_not_replayed(tmp_path, monkeypatch):
    import nodegraph.rerun_log

    monkeypatch.chdir(tmp_path)
    (tmp_path / "replay.yaml").write_text(RECIPE)
    assert run(tmp_path, "--rrd", "old.rrd") == 0
    before = {node: record["loggers"] for node, record in fragments(tmp_path).items()}
    monkeypatch.setattr(nodegraph.rerun_log, "logger_digest", lambda: "a-changed-logger")
    assert run(tmp_path, "--rrd", "new.rrd") == 0  # outputs logged again by today's loggers, fragments replaced
    after = {node: record["loggers"] for node, record in fragments(tmp_path).items()}
    assert set(before.values()) != {"a-changed-logger"} and set(after.values()) == {"a-changed-logger"}
    assert {"/surf/mesh", "/pts/0/spheres"} <= entities(tmp_path / "new.rrd")
    # what the nodes logged as they ran is their code's, not the loggers': carried over, not lost
    steps = energy_steps(tmp_path / "old.rrd", "/slow/log/energy")
    assert steps and energy_steps(tmp_path / "new.rrd", "/slow/log/energy") == steps
    assert energy_steps(tmp_path / "new.rrd", "/slow_twin/log/energy") == steps  # the twin's, moved to its path
    assert run(tmp_path, "--rrd", "again.rrd") == 0  # and kept in the new fragments
    assert energy_steps(tmp_path / "again.rrd", "/slow/log/energy") == steps
