"""The docs' measured tables are rendered from ``benchmarks/measured/*.jsonl``; a figure edited by hand fails here."""

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FIELDS = {"what", "command", "values", "unit", "load", "date", "machine"}


def tool():
    spec = importlib.util.spec_from_file_location("measured_tables", ROOT / "tools" / "measured_tables.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_measured_table_in_the_docs_equals_its_data():
    tables = tool()
    stale = [str(p.relative_to(ROOT)) for p in tables.documents() if tables.rewrite(p.read_text()) != p.read_text()]
    assert not stale, f"{stale}: a table differs from benchmarks/measured/: run `python tools/measured_tables.py`"


def test_every_table_is_shown_and_every_record_says_how_it_was_measured():
    tables = tool()
    shown = {m.group("name") for p in tables.documents() for m in tables.MARKER.finditer(p.read_text())}
    assert shown == set(tables.TABLES), f"declared but not shown: {set(tables.TABLES) - shown}"
    for file in {file for file, _, _ in tables.TABLES.values()}:
        for line in (tables.MEASURED / file).read_text().splitlines():
            missing = FIELDS - set(json.loads(line))
            assert not missing, f"{file}: a record without {sorted(missing)}"
