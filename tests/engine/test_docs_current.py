"""docs/nodes.md is generated from the node declarations; it must not drift from them."""

from pathlib import Path

from nodegraph.cli import markdown_reference
from nodegraph.registry import default_registry

DOCS = Path(__file__).resolve().parents[2] / "docs" / "nodes.md"


def test_node_reference_is_current():
    expected = markdown_reference(default_registry())
    assert DOCS.read_text() == expected, "docs/nodes.md is stale: run `nodegraph docs --out docs/nodes.md`"
