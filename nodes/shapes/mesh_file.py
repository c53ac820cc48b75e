"""The ``mesh_file`` node: any user mesh as a target shape (G's rice bunny) — SPEC §2 inputs."""

from __future__ import annotations

from nodegraph.node import Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh


def _check(params: dict) -> list[tuple[str, str]]:
    from ..mesh_io import file_problem

    problem = file_problem(params["path"])
    return [] if problem is None else [("path", problem)]


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
)
def mesh_file(ctx, *, path, size, center, repair):
    """Load a closed mesh; an open or inside-out one is repaired (``repair``) or refused with a clear error."""
    from .closed_mesh import closed_mesh, load_mesh

    mesh = closed_mesh(load_mesh(path), repair=repair, what=f"mesh_file {path!r}")
    if center:
        mesh.apply_translation(-mesh.bounds.mean(axis=0))
    if size > 0:
        import numpy as np

        mesh.apply_scale(size / np.linalg.norm(mesh.vertices - mesh.centroid, axis=1).max())
    return Mesh.from_trimesh(mesh, name=path.rsplit("/", 1)[-1])
