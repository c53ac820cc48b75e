"""The engine (``nodegraph/``) imports no node package and names no food: the domain lives in ``nodes/``."""

import ast
import re
import subprocess
import sys
from pathlib import Path

ENGINE = Path(__file__).resolve().parents[2] / "nodegraph"
FOOD = re.compile(
    r"\b(rice|grains?|ikura|eggs?|yolks?|roe|onigiri|sushi|kakigori|bowl|japonica|indica|chestnut)\b", re.IGNORECASE
)


def test_no_engine_module_imports_a_node_package():
    for path in sorted(ENGINE.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module or ""]
            else:
                continue
            assert not any(n == "nodes" or n.startswith("nodes.") for n in names), f"{path.name}:{node.lineno}"


def test_engine_sources_name_no_food():
    for path in sorted(ENGINE.glob("*.py")):
        for number, line in enumerate(path.read_text().splitlines(), 1):
            assert not FOOD.search(line), f"{path.name}:{number}: {line.strip()}"


def test_importing_the_engine_loads_no_node_package():
    probe = (
        "import sys, nodegraph.api, nodegraph.cli; print(sorted(m for m in sys.modules if m.split('.')[0] == 'nodes'))"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
