"""How the built-in value types appear in Rerun: registered on the engine's ``log_value`` dispatch.

Element libraries laid out in a row, sphere sets and volume cells as points, placements as points and
normals, aggregates as one mesh, particles as points, shaded scenes mesh by mesh (SPEC §1–4 outputs).
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np

from nodegraph.context import EntityLogger
from nodegraph.rerun_log import log_value, rerun_module

from .values import Aggregate, DistanceField, ElementLibrary, ParticleState, Placement, ShadedScene, SphereSet, Volume

MAX_VOLUME_POINTS = 200_000


@log_value.register
def _(value: ElementLibrary, log: EntityLogger) -> None:
    # Lay the elements out on a row so the whole library can be seen at once.
    offset = 0.0
    for i, mesh in enumerate(value.meshes):
        lo, hi = mesh.bounds
        shift = np.array([offset - lo[0], 0.0, 0.0])
        log_value(dataclasses.replace(mesh, vertices=mesh.vertices + shift), log.child(f"{i}"))
        offset += (hi[0] - lo[0]) * 1.2


@log_value.register
def _(value: SphereSet, log: EntityLogger) -> None:
    rr = rerun_module()
    log.log("", rr.Points3D(value.centers.astype(np.float32), radii=value.radii.astype(np.float32)), static=True)


@log_value.register
def _(value: Volume, log: EntityLogger) -> None:
    """Inside cells as points (subsampled; a distance field coloured by depth) and the middle z-slice."""
    rr = rerun_module()
    data = np.asarray(value.data)
    inside = data > 0
    step = max(1, int(np.ceil(np.count_nonzero(inside) / MAX_VOLUME_POINTS)))
    centers = value.cell_centers(inside)[::step].astype(np.float32)
    colors = None
    if isinstance(value, DistanceField) and len(centers):
        depth = data[inside][::step]
        shade = (255 * depth / depth.max()).astype(np.uint8)
        colors = np.stack([shade, 64 + shade // 2, 255 - shade], axis=1).astype(np.uint8)
    log.log("cells", rr.Points3D(centers, colors=colors, radii=np.float32(value.voxel_size * 0.5)), static=True)
    middle = data[:, :, data.shape[2] // 2].astype(np.float32)
    span = float(np.abs(middle).max()) or 1.0
    log.log("slice", rr.Tensor(middle / span), static=True)


@log_value.register
def _(value: Placement, log: EntityLogger) -> None:
    rr = rerun_module()
    log.log(
        "positions",
        rr.Points3D(value.positions.astype(np.float32), class_ids=value.kinds.astype(np.uint16)),
        static=True,
    )
    if len(value):
        log.log(
            "normals",
            rr.Arrows3D(origins=value.positions.astype(np.float32), vectors=value.normals.astype(np.float32) * 0.5),
            static=True,
        )


def elements_mesh3d(value: Aggregate):
    """Every element of the aggregate in world space as one ``Mesh3D`` (None when empty)."""
    mesh = value.combined_mesh()
    if mesh is None:
        return None
    return rerun_module().Mesh3D(
        vertex_positions=mesh.vertices.astype(np.float32), triangle_indices=mesh.faces.astype(np.uint32)
    )


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


@log_value.register
def _(value: Aggregate, log: EntityLogger) -> None:
    """Elements drawn by instancing (``log_element_poses``), so the recording (and a cached re-run's replay)
    holds each library mesh once, not every element's vertices. Flattened contacts are left out here: the
    dented surfaces are logged once, with the shaded scene. An aggregate with bends (SPEC §5 quadratic), or
    whose parts cannot be split, is logged as one world-space mesh."""
    from .simulation.aggregate import DeformedAggregate

    exact = type(value) in (Aggregate, DeformedAggregate) and value.bends is None
    if not (exact and log_element_poses(log, value, static=True)):
        archetype = elements_mesh3d(value)
        if archetype is not None:
            log.log("elements", archetype, static=True)


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
    names = ["_".join(_entity_parts(library.kind)) or "kind" for library in value.libraries]
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


@log_value.register
def _(value: ParticleState, log: EntityLogger) -> None:
    rr = rerun_module()
    log.log(
        "",
        rr.Points3D(
            value.positions.astype(np.float32),
            radii=value.radii.astype(np.float32),
            class_ids=(value.element % 65535).astype(np.uint16),
        ),
        static=True,
    )


def _entity_parts(name: str) -> list[str]:
    """Entity path parts from a mesh name like ``japonica/0012`` or ``ikura/0003/yolk`` (unsafe characters
    replaced)."""
    parts = [re.sub(r"[^A-Za-z0-9_.-]", "_", part) for part in name.split("/") if part]
    return parts


@log_value.register
def _(value: ShadedScene, log: EntityLogger) -> None:
    """Each mesh under its name (``/shade/scene/japonica/0012``, ``…/ikura/0003/yolk``, ``…/bowl_container``),
    with its element kind and material as properties."""
    rr = rerun_module()
    for i, mesh in enumerate(value.meshes):
        parts = _entity_parts(mesh.name) or [f"mesh_{i:04d}"]
        child = log.child("/".join(parts))
        log_value(mesh, child)
        material = value.materials[value.material_of[i]]
        child.log("", rr.AnyValues(kind=parts[0], material=material.name), static=True)
