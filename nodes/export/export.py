"""The ``export`` node: a shaded scene as glTF binary, USD, PLY and OBJ bytes — SPEC §4 output.

Returns a ``FileSet``; the engine writes it atomically into ``outputs/<recipe>/`` (temp + rename),
so an unwritable destination leaves nothing half-written.
"""

from __future__ import annotations

import re

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, loads_libraries, node
from nodegraph.params import RECIPE_FILE_NAME, Param
from nodegraph.values import FileSet

from ..values import ShadedScene

FORMATS = ("glb", "usda", "usdc", "ply", "obj")


def _load_libraries() -> None:
    """The export's native libraries (``NodeSpec.libraries``): USD's."""
    from .usd_writer import load_libraries

    load_libraries()


def _check(params):
    problems = []
    bad = [f for f in params.get("formats", ()) if f not in FORMATS]
    if not params.get("formats"):
        problems.append(("formats", "name at least one of " + ", ".join(FORMATS)))
    if bad:
        problems.append(("formats", f"unknown format(s) {bad}; allowed: {', '.join(FORMATS)}"))
    if not re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9_.-]*", params.get("basename", "")):
        problems.append(("basename", "a plain file name: letters, digits, '_', '-', '.' (no folders)"))
    return problems


@estimated_by(passes("scene"))
@loads_libraries(_load_libraries)
@node(
    "export",
    # its files are the largest entry of a run and quicker made than stored: the full main job's .glb and .usdc,
    # 107.5 MB, made in 1.47 s, stored in 3.8 s (78.7 MB, 62 % of what the run caches) and loaded in 1.3 s
    # (benchmarks/measured/cache.jsonl); the run's own folder keeps them
    store=False,
    inputs={"scene": In(ShadedScene, "shaded meshes with materials")},
    outputs={"files": Out(FileSet, "<basename>.<format> for each requested format")},
    params={
        "formats": Param(list[str], ["glb", "usdc"], f"file formats, any of {', '.join(FORMATS)}"),
        "basename": Param(
            str, RECIPE_FILE_NAME, "file name without extension (a plain name, no folders; a copied recipe's own)"
        ),
        "instancing": Param(
            bool,
            True,
            "write meshes that are one mesh moved rigidly (elements no contact, shape matching or bending changed) "
            "once, as instances: a USD PointInstancer, glTF nodes sharing one mesh; false: a mesh per element",
        ),
    },
    check=_check,
)
def export(ctx, scene, *, formats, basename, instancing):
    """glb: core PBR + KHR_materials_* (glTF-Validator clean); USD: UsdPreviewSurface; PLY/OBJ: sRGB colours;
    glb and USD instance rigid copies of one mesh (``instancing.instance_groups``)."""
    problems = _check({"formats": formats, "basename": basename})
    if problems:
        raise ValueError("; ".join(f"{name}: {message}" for name, message in problems))
    from .gltf_writer import glb_bytes, material_translucency
    from .instancing import instance_groups
    from .mesh_files import obj_bytes, ply_bytes
    from .usd_writer import usd_bytes

    groups = weights = None
    if {"glb", "usda", "usdc"} & set(formats):  # found once for the .glb and the USD files
        groups, weights = instance_groups(scene) if instancing else [], material_translucency(scene)
    writers = {
        "glb": lambda s: glb_bytes(s, instancing, groups, weights),
        "usda": lambda s: usd_bytes(s, binary=False, instancing=instancing, groups=groups, weights=weights),
        "usdc": lambda s: usd_bytes(s, binary=True, instancing=instancing, groups=groups, weights=weights),
        "ply": ply_bytes,
        "obj": obj_bytes,
    }
    return FileSet({f"{basename}.{fmt}": writers[fmt](scene) for fmt in dict.fromkeys(formats)})
