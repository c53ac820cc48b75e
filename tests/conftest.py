"""Shared fixtures for shading/export tests: a small synthetic aggregate (capsule grains + ikura eggs
with membrane/yolk parts, a bowl) and the Khronos glTF-Validator, installed once per session."""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
VALIDATOR_DIR = REPO / ".cache" / "gltf-validator"
VALIDATOR_VERSION = "2.0.0-dev.3.10"


@pytest.fixture(scope="session")
def scene_inputs():
    import trimesh

    from nodegraph.context import Context
    from nodegraph.values import Aggregate, ElementLibrary, Mesh, Placement
    from nodes.elements import base_mesh
    from nodes.shapes import shape

    ctx = Context.standalone(seed=0)
    bowl = shape(ctx, **shape.resolve_params({"kind": "bowl", "size": 12.0, "depth": 8.0, "mound": 2.0,
                                              "resolution": 2}))
    egg = base_mesh(ctx, **base_mesh.resolve_params({"shape": "ikura", "subdivisions": 1}))
    grain = Mesh.from_trimesh(trimesh.creation.capsule(height=3.0, radius=1.0, count=[8, 8]))
    g = np.linspace(-6, 6, 4)
    xy = np.array([(x, y) for x in g for y in g])
    rice = Aggregate(Placement(np.c_[xy, np.full(len(xy), -3.0)], np.tile([0, 0, 1.0], (len(xy), 1)),
                               kind_names=("japonica",)), (ElementLibrary("japonica", (grain,)),))
    eggs = Aggregate(Placement([[0, 0, 0.5], [3, 0, 0.5], [-3, 1, 0.5]], np.tile([0, 0, 1.0], (3, 1)),
                               kind_names=("ikura",)), (ElementLibrary("ikura", (egg,)),))
    return {"aggregates": [rice, eggs], "scenery": [bowl["container"]]}


@pytest.fixture(scope="session")
def shaded(scene_inputs):
    from nodegraph.context import Context
    from nodes.shading import shade

    return shade(Context.standalone(seed=0), **scene_inputs, **shade.resolve_params({}))


@pytest.fixture(scope="session")
def gltf_validator():
    """A function bytes → report (dict) running Khronos glTF-Validator under Node.js."""
    if shutil.which("npm") is None or shutil.which("node") is None:
        pytest.skip("npm/node not found: the Khronos glTF-Validator (npm package gltf-validator) cannot be installed")
    package = VALIDATOR_DIR / "node_modules" / "gltf-validator"
    if not package.exists():
        subprocess.run(["npm", "install", "--no-audit", "--no-fund", "--prefix", str(VALIDATOR_DIR),
                        f"gltf-validator@{VALIDATOR_VERSION}"], check=True, capture_output=True, timeout=300)
    script = ("const v = require(process.argv[1]); const fs = require('fs');"
              "v.validateBytes(new Uint8Array(fs.readFileSync(0))).then(r => console.log(JSON.stringify(r.issues)));")

    def validate(data: bytes) -> dict:
        import json

        done = subprocess.run(["node", "-e", script, str(package)], input=data, capture_output=True, timeout=120,
                              check=True)
        return json.loads(done.stdout)

    return validate
