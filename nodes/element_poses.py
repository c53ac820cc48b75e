"""Elements as instanced library meshes in Rerun: each library mesh logged once, a pose per element — what
the aggregate logger (``nodes.rerun_loggers``) and the simulation's per-step snapshots (``xpbd``) record
instead of every element's vertices."""

from __future__ import annotations

import re

import numpy as np

from nodegraph.context import EntityLogger
from nodegraph.rerun_log import rerun_module

from .values import Aggregate


def entity_parts(name: str) -> list[str]:
    """Entity path parts from a mesh name like ``japonica/0012`` or ``ikura/0003/yolk`` (unsafe characters
    replaced)."""
    parts = [re.sub(r"[^A-Za-z0-9_.-]", "_", part) for part in name.split("/") if part]
    return parts


def _instance_groups(value: Aggregate, mesh) -> list[tuple[str, np.ndarray, bool]] | None:
    """How one library mesh is drawn by instancing: (entity suffix, its faces, moved by the part offset).
    A part-offset aggregate (the yolk that rose inside its egg) splits the mesh into its part-1 faces and
    the rest; None when it cannot be instanced exactly (the two share vertices)."""
    offsets = getattr(value, "part_offsets", None)
    if offsets is None or mesh.parts is None or not np.any(mesh.parts == 1):
        return [("", mesh.faces, False)]
    moved, rest = mesh.faces[mesh.parts == 1], mesh.faces[mesh.parts != 1]
    if np.intersect1d(moved, rest).size:
        return None
    return [("rest", rest, False), ("part1", moved, True)]


def log_element_poses(log: EntityLogger, value: Aggregate, static: bool) -> bool:
    """Each library mesh once (static) at ``elements/<kind>/<mesh>`` with a pose per element that uses it: its
    linear map D·R and position t (SPEC §3's x = D·R·v + t; a displaced inner part also moved by its offset).
    ``static`` False logs the poses at the logger's current time (a simulation step), the meshes only the
    first time. Bends and dents are not drawn. False (nothing logged) when a mesh's parts cannot be split."""
    p = value.placement
    plans = [[_instance_groups(value, mesh) for mesh in library.meshes] for library in value.libraries]
    if None in sum(plans, []):
        return False
    rr = rerun_module()
    linear = (p.rotations if value.deformations is None else value.deformations @ p.rotations).astype(np.float32)
    names = ["_".join(entity_parts(library.kind)) or "kind" for library in value.libraries]
    for kind, library in enumerate(value.libraries):
        name = names[kind] if names.count(names[kind]) == 1 else f"{names[kind]}_{kind}"
        for m, mesh in enumerate(library.meshes):
            use = np.flatnonzero((p.kinds == kind) & (p.variants % len(library) == m))
            for suffix, faces, moved in plans[kind][m] if len(use) else []:
                child = log.child("/".join(x for x in ("elements", name, f"{m:03d}", suffix) if x))
                if static or log.index is None or "Mesh3D" not in log.index.archetypes.get(child.path(""), ()):
                    kept, local = np.unique(faces, return_inverse=True)  # this group's vertices, re-indexed
                    mesh3d = rr.Mesh3D(
                        vertex_positions=mesh.vertices[kept].astype(np.float32),
                        triangle_indices=local.reshape(-1, 3).astype(np.uint32),
                    )
                    child.log("", mesh3d, static=True)
                at = p.positions[use] + (value.part_offsets[use] if moved else 0.0)
                poses = rr.InstancePoses3D(translations=at.astype(np.float32), mat3x3=linear[use])
                child.log("", poses, static=static)
    return True
