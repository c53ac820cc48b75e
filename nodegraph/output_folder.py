"""Where a recipe's outputs go unless --out-dir says: a folder of its own per recipe file, so that a copy of a
recipe (another folder, the same name) never overwrites the outputs of the one it was copied from."""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

PROJECT_MARKERS = ("pyproject.toml", ".git")
MANIFEST = "manifest.json"  # output_files.MANIFEST: the run that wrote a folder names its recipe file there


DRAFT_SUFFIX = "_draft"  # a --draft run's folder is its recipe's name and this: drafts never mix with the final


PLAIN_NAME = re.compile(r"^(?!.*\.\.)[A-Za-z0-9_-][A-Za-z0-9_.-]*$")  # a folder name: no separator, no ``..``


def recipe_file_name(recipe_path: Path, name: str) -> str:
    """What a run of the recipe file ``recipe_path`` whose ``name:`` is ``name`` names its folder, recording and
    files after: the file's stem, so a copy of a recipe under another file name names them after itself, never
    after the original (the recipe as written, ``NAME.yaml`` of ``name: NAME``, gets ``NAME``); ``name`` where the
    stem is not a plain name."""
    stem = Path(recipe_path).stem
    return stem if PLAIN_NAME.match(stem) else name


def recipe_folder_name(recipe_path: Path, name: str, draft: bool) -> str:
    """The output folder's name of a run of the recipe (its sweeps go into a ``sweeps/`` folder inside):
    ``recipe_file_name``, and ``_draft`` for a draft."""
    return recipe_file_name(recipe_path, name) + (DRAFT_SUFFIX if draft else "")


SETTINGS_PREFIX = "set_"  # a --set run's folder, inside its recipe's: set_<its settings>
SETTINGS_NAME_MAX = 80  # characters of a settings folder's name; a longer one is cut and ends with a hash
SETTINGS_DROPPED = " \t[]{}()'\""  # spacing, brackets and quotes: a value reads the same without them
SETTINGS_UNSAFE = re.compile(r"[^A-Za-z0-9._=,+-]+")  # what a file name may not hold: a path's separators, ...


def settings_folder(folder: Path, overrides) -> Path:
    """Where a run with the ``--set`` texts ``overrides`` writes: ``folder`` (the recipe's own) when there are none,
    else a folder inside it named from them (``set_cooked.water_content=22``; several joined by ``+``; spacing,
    brackets and quotes dropped; each run of other characters a file name may not hold, such as a path's ``/``,
    written ``_``: ``set_mesh.path=scans_cat.obj-<hash>``), so that runs with other settings never replace or remove
    each other's files: each set of settings keeps its own folder, the recipe as written ``folder`` itself, and a
    run replaces only what an earlier run of the same settings wrote there (``output_files.settle_earlier``). A name
    whose characters were replaced (``a/b`` and ``a_b`` would meet) or longer than ``SETTINGS_NAME_MAX`` (then cut)
    ends with a hash of the texts."""
    if not overrides:
        return folder
    kept = ["".join(c for c in text if c not in SETTINGS_DROPPED) for text in overrides]
    texts = [SETTINGS_UNSAFE.sub("_", text) for text in kept]
    name = SETTINGS_PREFIX + "+".join(texts)
    replaced = texts != kept
    if replaced or len(name) > SETTINGS_NAME_MAX:
        digest = hashlib.sha256("\n".join(overrides).encode()).hexdigest()[:8]
        name = name[: SETTINGS_NAME_MAX - 9] + "-" + digest
    return folder / name


def outputs_root(recipe_path: Path) -> Path:
    """``outputs/`` of the recipe's project (the nearest folder above the recipe holding a pyproject.toml or .git:
    this repository for graphs/*.yaml), else beside the recipe; whichever folder the command runs in. Shown
    relative to the current folder where it lies below it."""
    recipe_dir = Path(recipe_path).resolve().parent
    root = next((d for d in (recipe_dir, *recipe_dir.parents) if any((d / m).exists() for m in PROJECT_MARKERS)), None)
    folder = (root or recipe_dir) / "outputs"
    try:
        return folder.relative_to(Path.cwd().resolve())
    except ValueError:
        return folder


def recipe_folder(recipe_path: Path, name: str, draft: bool = False) -> Path:
    """``outputs/<folder>/`` of the recipe's project (``recipe_folder_name``: the file's stem, ``_draft`` for a
    draft), unless a run of another recipe file wrote it (its manifest names that file; a recipe of the same file
    name in another folder): then ``outputs/<folder>-<hash>/``, the hash of this file's resolved path, the same on
    every run, so each recipe file keeps one folder of its own."""
    name = recipe_folder_name(recipe_path, name, draft)
    root = outputs_root(recipe_path)
    plain = root / name
    mine = Path(recipe_path).resolve()
    owner = folder_owner(plain, root.resolve().parent)
    if owner is None or owner == mine:
        return plain
    return root / f"{name}-{hashlib.sha256(str(mine).encode()).hexdigest()[:8]}"


def folder_owner(folder: Path, project: Path) -> Path | None:
    """The resolved recipe file whose run wrote ``folder`` (its manifest's ``recipe_file``; a relative one, as
    runs before this rule wrote, taken from the project or the current folder, whichever exists); None when no
    run wrote it or that file is gone."""
    try:
        given = json.loads((folder / MANIFEST).read_bytes())["recipe_file"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    path = Path(given)
    candidates = [path] if path.is_absolute() else [project / path, Path.cwd() / path]
    return next((p.resolve() for p in candidates if p.is_file()), None)
