"""Parameters that name input files: the file must exist, and its content is part of the cache key."""

from nodegraph.executor import run_recipe
from nodegraph.recipe import parse_recipe

from .test_validation import issues_of

RECIPE = """\
name: lines
outputs: [read.table]
nodes:
  read:
    type: toy_file_table
    params: {{path: {path}}}
"""


def _run(path, registry, cache):
    result = run_recipe(parse_recipe(RECIPE.format(path=path), registry, file="r.yaml"), cache=cache)
    return result.output("read.table").columns["length"].tolist(), {r.node: r.status for r in result.records}


def test_an_edited_input_file_is_read_again_and_an_unchanged_one_is_cached(tmp_path, registry, cache):
    data = tmp_path / "lines.txt"
    data.write_text("a\nbb\n")
    assert _run(data, registry, cache) == ([1, 2], {"read": "ran"})
    assert _run(data, registry, cache) == ([1, 2], {"read": "cached"})
    data.write_text("a\nbb\nccc\n")  # same name, new content
    assert _run(data, registry, cache) == ([1, 2, 3], {"read": "ran"})


def test_a_missing_input_file_is_a_validation_error_at_its_line(tmp_path, registry):
    issues = issues_of(RECIPE.format(path=tmp_path / "nope.txt"), registry)
    assert len(issues) == 1
    assert issues[0].location.line == 6 and issues[0].param == "path" and "no such file" in issues[0].message
    assert "existing file" in issues[0].allowed


def test_a_folder_given_as_a_file_is_named_a_folder_with_the_types_accepted(tmp_path, registry):
    """Issue 47: a folder passed as a mesh path said "no such file"."""
    (tmp_path / "lines.txt").write_text("a\n")
    (tmp_path / "notes.md").write_text("b\n")
    (issue,) = issues_of(RECIPE.format(path=tmp_path), registry)
    assert issue.location.line == 6 and issue.param == "path"
    assert issue.message == f"{tmp_path} is a folder, not a file"
    assert issue.allowed == "a file of type .txt, .csv; in that folder: lines.txt"
