"""The ``mesh_file`` node: any user mesh as a target shape (G's rice bunny) — SPEC §2 inputs."""

from __future__ import annotations

from nodegraph.node import Out, node, warns_of
from nodegraph.params import Param
from nodegraph.values import Mesh

from ..mesh_io import repair_line


def _check(params: dict) -> list[tuple[str, str]]:
    from ..mesh_io import file_problem

    problem = file_problem(params["path"])
    return [] if problem is None else [("path", problem)]


def repaired(path: str, repair: bool) -> tuple[object, list[str]]:
    """The closed mesh read from ``path`` (``closed_mesh``) and what was changed to make it one, in words."""
    from .closed_mesh import closed_mesh, load_mesh

    changes: list[str] = []
    mesh = closed_mesh(load_mesh(path, changes), repair=repair, what=f"mesh_file {path!r}", changes=changes)
    return mesh, list(dict.fromkeys(changes))


def _readable(node_id: str, nodes) -> list[tuple[str, str, bool]]:
    """A file that exists but is no closed mesh (no triangles, open past repair, damaged), refused by ``nodegraph
    check`` at ``path`` with the reader's reason, before the estimate reads it (its placement weighs the shape)."""
    params = nodes[node_id].params
    try:
        repaired(params["path"], params["repair"])
    except ValueError as refused:
        return [("path", str(refused).removeprefix("path: "), False)]
    return []


def _warns(node_id: str, nodes) -> list[tuple[str, str]]:
    """What a run will say of the mesh file (``nodegraph check``): its repairs; nothing where it cannot be read
    (the parameter's own check says why)."""
    params = nodes[node_id].params
    try:
        _, changes = repaired(params["path"], params["repair"])
    except ValueError:
        return []
    return [("path", repair_line(params["path"], changes))] if changes else []


@warns_of(_warns)
@node(
    "mesh_file",
    outputs={"mesh": Out(Mesh, "the closed user mesh, outward normals")},
    params={
        "path": Param(str, doc="mesh file (.stl, .obj, .ply, .off, .glb, .gltf) readable by trimesh", file=True),
        "size": Param(
            float,
            0.0,
            "scale so the circumscribed radius about the centroid is this (0: keep the file's units)",
            range=(0.0, 1e5),
            units="mm",
        ),
        "center": Param(bool, True, "move the bounding-box centre to the origin"),
        "repair": Param(bool, True, "fix inverted normals and fill small holes instead of refusing the mesh"),
    },
    check=_check,
    check_work=_readable,
)
def mesh_file(ctx, *, path, size, center, repair):
    """Load a closed mesh; an open or inside-out one is repaired (``repair``, said as a warning) or refused with a
    clear error."""
    mesh, changes = repaired(path, repair)
    if changes:
        ctx.warn(repair_line(path, changes))
    if center:
        mesh.apply_translation(-mesh.bounds.mean(axis=0))
    if size > 0:
        import numpy as np

        mesh.apply_scale(size / np.linalg.norm(mesh.vertices - mesh.centroid, axis=1).max())
    return Mesh.from_trimesh(mesh, name=path.rsplit("/", 1)[-1])
