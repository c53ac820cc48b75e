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
    files = [(file,) if isinstance(file, str) else file for file, _, _ in tables.TABLES.values()]
    for file in {f for group in files for f in group}:
        for line in (tables.MEASURED / file).read_text().splitlines():
            missing = FIELDS - set(json.loads(line))
            assert not missing, f"{file}: a record without {sorted(missing)}"


def test_the_readme_and_the_gallery_say_counts_and_times_only_from_the_data():
    """Issue 47: the README said 244 eggs, the scene table 562 eggs, the gallery 1,889 elements in 199 s against the
    scene table's 39.7 s, and the README "about 2 minutes the first time". Outside the tables rendered from
    benchmarks/measured/, neither says a count of elements or a run's time."""
    import re

    tables = tool()
    counted = re.compile(r"\d[\d,]* (eggs|grains|flakes|elements)\b|\d+ s \(load|\d+ (minutes|s) (once|the first)")
    for doc in (ROOT / "README.md", ROOT / "docs" / "images" / "gallery.md"):
        text = tables.MARKER.sub("", doc.read_text())
        assert not counted.search(text), f"{doc.name}: {counted.search(text).group(0)!r} said by hand"
    rows = [json.loads(line) for line in (tables.MEASURED / "scenes.jsonl").read_text().splitlines()]
    main = next(r for r in rows if r["recipe"] == "ikura_don")
    assert "readme" in main  # the README's time of the main job is the scene table's
