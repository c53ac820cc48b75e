"""CI runs exactly the test command README gives a newcomer."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def readme_test_command() -> str:
    lines = (ROOT / "README.md").read_text().splitlines()
    start = lines.index("<!-- test-command -->")
    assert lines[start + 1] == "```bash"
    return lines[start + 2]


def test_ci_runs_readme_test_command():
    command = readme_test_command()
    assert "pytest" in command
    ci_lines = [line.strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert command in ci_lines


def test_readme_starts_with_the_two_commands_and_stays_short():
    """Issue 47: README was 8,266 words and the one command a newcomer needs was buried. It starts with the main
    job's command and the test command, a code block each, before any section; the rest is in docs/."""
    text = (ROOT / "README.md").read_text()
    before_sections = text.split("\n## ")[0]
    blocks = before_sections.split("```bash\n")[1:]
    commands = [block.split("\n")[0] for block in blocks]
    assert len(commands) == 2, before_sections
    assert commands[0].endswith("pip install -e . && nodegraph run graphs/ikura_don.yaml")
    assert commands[1] == readme_test_command()
    assert len(text.split()) < 1500


def test_the_readme_and_reference_links_resolve():
    import re

    for doc in (ROOT / "README.md", ROOT / "docs" / "reference.md"):
        for target in re.findall(r"\]\(([^)#]+)\)", doc.read_text()):
            if not target.startswith("http"):
                assert (doc.parent / target).exists(), f"{doc.name}: {target}"


def test_every_metric_suffix_readme_uses_is_in_the_sweep_help(capsys):
    """README's sweep example ends its metric with ``:higher``; a new user found only the aggregates in --help."""
    import re

    import pytest

    from nodegraph.cli import main

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    suffixes = {m.group(1) for m in re.finditer(r"--metric \S+?:(\w+)", readme)}
    assert suffixes
    with pytest.raises(SystemExit):
        main(["sweep", "--help"])
    shown = capsys.readouterr().out
    assert all(f":{s}" in shown or f" {s}," in shown for s in suffixes), (suffixes, shown)
