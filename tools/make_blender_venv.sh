#!/usr/bin/env bash
# Make a separate virtual environment with Blender as a Python module (bpy) for the Blender round-trip test
# (tests/export/test_blender_roundtrip.py) and for scripting Blender imports outside Blender.
#
# bpy 4.5 (Blender 4.5 LTS) pins numpy 1.26 and the project uses numpy 2, so bpy cannot share the project's
# venv. Usage: tools/make_blender_venv.sh [VENV_DIR]   (default .venv-blender; NODEGRAPH_BLENDER_PYTHON
# or the default folder is where the test looks). Needs CPython 3.11, the only Python bpy 4.5 is built for.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${1:-.venv-blender}"
python="${PYTHON:-python3.11}"
command -v "$python" >/dev/null || python=python3
version=$("$python" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')
if [ "$version" != "3.11" ]; then
    echo "bpy 4.5 needs CPython 3.11; $python is $version (set PYTHON=/path/to/python3.11)" >&2
    exit 2
fi
start=$(date +%s)
"$python" -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet "bpy==4.5.*"
"$venv/bin/python" -c 'import bpy; print("bpy", bpy.app.version_string, "in", __import__("sys").prefix)'
echo "made $venv in $(( $(date +%s) - start )) s"
