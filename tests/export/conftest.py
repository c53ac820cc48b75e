"""The Khronos glTF-Validator for the export tests, installed once per session (needs npm and node)."""

import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
VALIDATOR_DIR = REPO / ".cache" / "gltf-validator"
VALIDATOR_VERSION = "2.0.0-dev.3.10"


@pytest.fixture(scope="session")
def gltf_validator():
    """A function bytes → report (dict) running Khronos glTF-Validator under Node.js."""
    if shutil.which("npm") is None or shutil.which("node") is None:
        pytest.skip("npm/node not found: the Khronos glTF-Validator (npm package gltf-validator) cannot be installed")
    package = VALIDATOR_DIR / "node_modules" / "gltf-validator"
    if not package.exists():
        subprocess.run(
            [
                "npm",
                "install",
                "--no-audit",
                "--no-fund",
                "--prefix",
                str(VALIDATOR_DIR),
                f"gltf-validator@{VALIDATOR_VERSION}",
            ],
            check=True,
            capture_output=True,
            timeout=300,
        )
    script = (
        "const v = require(process.argv[1]); const fs = require('fs');"
        "v.validateBytes(new Uint8Array(fs.readFileSync(0))).then(r => console.log(JSON.stringify(r.issues)));"
    )

    def validate(data: bytes) -> dict:
        import json

        done = subprocess.run(
            ["node", "-e", script, str(package)], input=data, capture_output=True, timeout=120, check=True
        )
        return json.loads(done.stdout)

    return validate
