"""The elastic_body node and its recipes (SPEC §5, U §4.1): effect gating, spring-back, tearing into
closed pieces at every frame, cracks, determinism, export of the pieces."""

from pathlib import Path

import numpy as np
import pytest
import trimesh

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
from nodes.tearing import elastic_body
from nodes.tearing.body import BodySettings, ElasticBody
from nodes.tearing.elastic_body import pull_field
from nodes.tearing.surface_mesh import cube_surface

REPO = Path(__file__).resolve().parents[2]
TEAR = dict(frames=40, pull_direction=[1.0, 1.0, 1.0], pull_acceleration=1e5, pull_frames=40, hold=True)


def _closed(vertices, faces):
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    return mesh.is_watertight and mesh.is_winding_consistent


def test_without_the_tearing_effect_no_break_test_runs():
    out = elastic_body.call(effects=[], **TEAR)
    h = out["history"].columns
    assert np.all(h["tear_checks"] == 0) and np.all(h["pieces"] == 1) and h["max_stretch"].max() > 3.0
    torn = elastic_body.call(effects=["tearing"], **TEAR)
    t = torn["history"].columns
    assert np.array_equal(t["tear_checks"], t["frame"] * 10)  # one test per step (10 substeps)
    assert t["pieces"][-1] >= 2 and t["tears"][-1] >= 1


def test_elastic_block_springs_back():
    out = elastic_body.call(
        effects=[],
        frames=120,
        pull_direction=[1.0, 1.0, 1.0],
        pull_acceleration=3e4,
        pull_radius=2.5,
        pull_frames=30,
        hold=True,
    )
    h = out["history"].columns
    assert h["shape_error"][:30].max() > 5e-3  # deformed while pulled
    assert h["shape_error"][-1] < 1e-3 and h["max_stretch"][-1] < 1.05  # back to its rest shape
    assert np.all(np.isfinite(h["energy"])) and h["energy"][30:].max() <= h["energy"][30] * 1.001  # no growth
    assert _closed(out["mesh"].vertices, out["mesh"].faces)


def test_every_piece_is_closed_at_every_step_of_a_tear():
    vertices, faces = cube_surface(6, 20.0)
    accel, moving = pull_field(vertices, [1.0, 1.0, 1.0], 1e5, 0.0, True)
    body = ElasticBody(
        vertices, faces, 10.0, BodySettings(h=1 / 600, stiffness=2e4, beta=0.3, tearing=True), accel, moving
    )
    pieces = []
    for _ in range(600):
        body.step()
        assert np.all(np.isfinite(body.x))
        if body.calls["tear"]:
            body.accel[:] = 0.0
        pieces.append(body.n_clusters)
        assert all(_closed(v, f) for v, f in body.pieces())
    assert body.calls["tear"] >= 1 and pieces[-1] >= 2 and np.all(np.diff(pieces) >= 0)
    assert body.settings.threshold == 3.0  # U §4.1's default


@pytest.mark.parametrize("rule, pieces, openings", [("edge", 1, 1), ("vertex", 2, 2)])
def test_a_vertex_pulled_out_cracks_open_or_tears_its_fan_out(rule, pieces, openings):
    """One inner vertex lifted 5 edge lengths: rule 'edge' (U §4.3's cracks) breaks its spokes, the vertex
    splits and a star-shaped crack opens in a body still in one piece; U's rule 'vertex' tears its fan out."""
    vertices, faces = cube_surface(6, 6.0)
    top = np.flatnonzero(np.isclose(vertices[:, 2], 3.0) & (np.abs(vertices[:, :2]).max(1) < 0.5))[0]
    settings = BodySettings(h=1e-3, stiffness=0.0, tearing=True, rule=rule)  # α = 0: nothing moves back
    body = ElasticBody(vertices, faces, 1.0, settings)
    body.x[np.flatnonzero(np.all(body.x0 == vertices[top], axis=1))[0], 2] += 5.0
    assert body.step()
    assert body.n_clusters == pieces and len(body.loop_start) - 1 == openings
    assert all(_closed(v, f) for v, f in body.pieces())


def test_same_parameters_same_bits():
    a = elastic_body.call(effects=["tearing"], **TEAR)
    b = elastic_body.call(effects=["tearing"], **TEAR)
    assert np.array_equal(a["mesh"].vertices, b["mesh"].vertices) and np.array_equal(a["mesh"].faces, b["mesh"].faces)


@pytest.mark.parametrize("recipe", ["tear_block", "ikura_tear"])
def test_recipe_exports_torn_pieces_as_closed_meshes(recipe, tmp_path):
    loaded = load_recipe(REPO / "graphs" / f"{recipe}.yaml", default_registry(), [])
    result = run_recipe(loaded, cache=Cache(tmp_path / "cache"), out_dir=tmp_path / "out")
    glb = [p for p in result.files if p.suffix == ".glb"]
    scene = trimesh.load(glb[0])
    meshes = list(scene.geometry.values())
    assert len(meshes) >= 2 and all(m.is_watertight for m in meshes)
    usd = [p for p in result.files if p.suffix == ".usdc"]
    if recipe == "tear_block":  # and as USD, one mesh prim per piece
        from pxr import Usd, UsdGeom

        stage = Usd.Stage.Open(str(usd[0]))  # kept: its prims expire with it
        prims = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
        assert len(prims) == len(meshes)


def test_bad_parameters_are_refused_with_the_parameter_named():
    with pytest.raises(ValueError, match="pull_direction"):
        elastic_body.call(pull_direction=[0.0, 0.0, 0.0], frames=2)
    with pytest.raises(ValueError, match="not closed"):
        from nodegraph.values import Mesh

        elastic_body.call(mesh=Mesh(np.eye(3), [[0, 1, 2]]), frames=2, pull_frames=2)


def test_rerun_logs_the_mesh_per_step_coloured_by_cluster_with_tears_marked(tmp_path, monkeypatch):
    import datafusion
    from rerun.chunk import RrdReader

    from nodegraph.cli import main

    monkeypatch.chdir(tmp_path)
    rrd = tmp_path / "t.rrd"
    args = [
        "run",
        str(REPO / "graphs" / "tear_block.yaml"),
        "--set",
        "block.frames=20",
        "--set",
        "block.pull_frames=20",
        "--no-cache",
        "--rrd",
        str(rrd),
    ]
    assert main(args) == 0
    store = RrdReader(str(rrd)).stream().collect()
    ctx = datafusion.SessionContext()  # must outlive the queries
    body = store.reader("sim_step", contents="/block/log/body", ctx=ctx).to_arrow_table()
    assert body.column("sim_step").to_pylist() == [10 * f for f in range(21)]  # every frame, on the sim timeline
    colours = [
        np.unique(np.asarray(c), axis=0) for c in body.column("/block/log/body:Mesh3D:vertex_colors").to_pylist()
    ]
    assert len(colours[0]) == 1 and len(colours[-1]) >= 2  # one cluster, then the pieces in their own colours
    tears = store.reader("sim_step", contents="/block/log/tears", ctx=ctx).to_arrow_table()
    marked = [len(p) for p in tears.column("/block/log/tears:Points3D:positions").to_pylist()]
    assert marked[0] == 0 and marked[-1] > 0  # the openings' rims, once torn


@pytest.mark.parametrize("recipe", ["elastic_block", "tear_block", "tear_mesh", "ikura_tear"])
def test_recipes_validate_and_the_sphere_variant_is_one_set_away(recipe):
    loaded = load_recipe(REPO / "graphs" / f"{recipe}.yaml", default_registry(), [])
    assert ("tearing" in loaded.effects) == (recipe != "elastic_block")
    if recipe == "tear_block":
        sphere = load_recipe(REPO / "graphs" / "tear_block.yaml", default_registry(), ["block.shape=sphere"])
        assert sphere.nodes["block"].params["shape"] == "sphere"
