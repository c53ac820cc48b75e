"""The ``boolean`` node: difference / union / intersection of closed shapes with manifold3d — SPEC §2 inputs.

G cuts a sphere out of the rice bunny to show its filled cross-section; robust CSG comes from
manifold3d (exact, manifold output), not hand-written code.
"""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh

OPERATIONS = ("difference", "union", "intersection")


@node(
    "boolean",
    inputs={"a": In(Mesh, "first closed shape"), "b": In(Mesh, "second closed shape (subtracted for difference)")},
    outputs={"mesh": Out(Mesh, "the closed result")},
    params={"operation": Param(str, "difference", "a − b, a ∪ b or a ∩ b", choices=OPERATIONS)},
)
def boolean(ctx, a, b, *, operation):
    """Combine two closed meshes; an empty result is an error (nothing left to fill)."""
    import manifold3d
    import numpy as np
    import trimesh

    from .closed_mesh import as_trimesh

    solids = []
    for name, mesh in (("a", a), ("b", b)):
        tm = as_trimesh(mesh, f"boolean input {name}")
        solids.append(
            manifold3d.Manifold(
                manifold3d.Mesh(
                    vert_properties=np.asarray(tm.vertices, np.float32), tri_verts=np.asarray(tm.faces, np.uint32)
                )
            )
        )
    left, right = solids
    result = {"difference": lambda: left - right, "union": lambda: left + right, "intersection": lambda: left ^ right}[
        operation
    ]()
    if result.is_empty():
        raise ValueError(f"operation: the {operation} of the two shapes is empty")
    out = result.to_mesh()
    # as manifold3d gives it (closed, shared vertices): trimesh's processing merges vertices that lie closer than its
    # tolerance at a cut's slivers, which can open the mesh (the ikura don's egg layer in a 30 mm bowl)
    tm = trimesh.Trimesh(np.asarray(out.vert_properties)[:, :3], np.asarray(out.tri_verts), process=False)
    return Mesh.from_trimesh(tm, name=f"{operation}({a.name},{b.name})")
