"""Nothing a user made is lost, nothing is written where it should not be: the cases of issue 12, each
with its message and exit code, every user file left in place."""

from pathlib import Path

import pytest

from nodegraph.cli import main

TOY = str(Path(__file__).with_name("toy_nodes.py"))
RECIPE = "outputs: [pts]\nnodes:\n  pts: {type: toy_points, params: {count: 5}}\n"


def run(*args):
    return main([*args, "--plugin", TOY]) if args[0] != "cache" else main(list(args))


def test_cache_clear_refuses_a_directory_that_is_not_a_cache(tmp_path, capsys):
    thesis = tmp_path / "v" / "thesis.tex"
    thesis.parent.mkdir()
    thesis.write_text("years of work")
    assert run("cache", "clear", "--cache-dir", str(thesis.parent)) == 2
    assert "is not a nodegraph cache" in capsys.readouterr().err
    assert thesis.read_text() == "years of work"
    assert run("cache", "clear", "--cache-dir", str(thesis)) == 2  # a file
    assert "is a file" in capsys.readouterr().err and thesis.exists()


def test_cache_clear_empties_a_real_cache_and_keeps_what_else_is_there(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "r.yaml").write_text(RECIPE)
    cache = tmp_path / "c"
    assert run("run", "r.yaml", "--cache-dir", str(cache), "--no-rrd", "-q") == 0
    assert (cache / "CACHEDIR.TAG").is_file() and list(cache.glob("entries/*/*.json"))
    (cache / "notes.txt").write_text("mine")
    assert run("cache", "clear", "--cache-dir", str(cache), "--yes") == 0
    assert sorted(p.name for p in cache.iterdir()) == ["notes.txt"]


def test_read_only_output_and_cache_folders_are_named_before_any_compute(tmp_path, monkeypatch, capsys):
    import errno
    import tempfile

    from nodegraph import cache as cache_module

    monkeypatch.chdir(tmp_path)
    (tmp_path / "r.yaml").write_text(RECIPE)
    locked = tmp_path / "locked"
    real = tempfile.mkstemp

    def read_only(*args, dir=None, **kwargs):  # a read-only mount (root writes through chmod, so simulate it)
        if dir is not None and str(dir).startswith(str(locked)):
            raise OSError(errno.EROFS, "Read-only file system")
        return real(*args, dir=dir, **kwargs)

    monkeypatch.setattr(cache_module.tempfile, "mkstemp", read_only)
    assert run("run", "r.yaml", "--out-dir", str(locked / "out"), "--no-rrd", "--no-cache") == 2
    err = capsys.readouterr().err
    assert f"cannot write the outputs at {locked / 'out'}: read-only file system" in err and "--out-dir" in err
    assert run("run", "r.yaml", "--cache-dir", str(locked / "cache"), "--no-rrd") == 2
    assert "cannot write the cache at" in capsys.readouterr().err
    assert not (tmp_path / "outputs" / "r" / "pts.npz").exists()  # refused before anything ran


def test_a_file_where_a_folder_is_expected_is_named_before_any_compute(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "r.yaml").write_text(RECIPE)
    (tmp_path / "blocker").write_text("a file")
    assert run("run", "r.yaml", "--cache-dir", str(tmp_path / "blocker" / "cache"), "--no-rrd", "-q") == 2
    err = capsys.readouterr().err
    assert "cannot write the cache at" in err and "a file is in the way" in err
    assert not (tmp_path / "outputs" / "r" / "pts.npz").exists()  # nothing was computed
    assert run("docs", "--out", str(tmp_path)) == 2
    assert "is a directory" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["/tmp/x", "../../x", "a/b", ".hidden", "x..y"])
def test_a_recipe_name_cannot_write_outside_the_output_root(tmp_path, monkeypatch, capsys, name):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "r.yaml").write_text(f"name: {name!r}\n" + RECIPE)
    assert run("check", "r.yaml") == 2
    err = capsys.readouterr().err
    assert "r.yaml:1:7" in err and "must be a plain name" in err


@pytest.mark.parametrize(
    "text, message",
    [
        (b"\xe9", "r.yaml:1:1: the recipe is not UTF-8 text"),
        (b"outputs: [b]\nnodes:\n  b: base_mesh\n", "r.yaml:3:6: node 'b': a node must be a mapping"),
        (b"outputs: [b]\nnodes:\n  b: [1, 2]\n", "r.yaml:3:6: node 'b': a node must be a mapping"),
        (b"outputs: [b]\nnodes:\n  b: {type: voxelise, params: {resolution: 1024}}\n", "out of range"),
    ],
)
def test_recipe_reading_failures_exit_2_with_file_and_line(tmp_path, capsys, text, message):
    (tmp_path / "r.yaml").write_bytes(text)
    assert main(["check", str(tmp_path / "r.yaml")]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
