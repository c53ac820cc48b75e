"""How the built-in value types appear in Rerun: registered on the engine's ``log_value`` dispatch.

Element libraries laid out in a row, sphere sets and volume cells as points, placements as points and
normals, aggregates as one mesh, particles as points, shaded scenes mesh by mesh (SPEC §1–4 outputs).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nodegraph.context import EntityLogger
from nodegraph.rerun_log import log_value, rerun_module

from .element_poses import entity_parts, log_element_poses
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


@log_value.register
def _(value: ShadedScene, log: EntityLogger) -> None:
    """Each mesh under its name (``/shade/scene/japonica/0012``, ``…/ikura/0003/yolk``, ``…/bowl_container``),
    with its element kind and material as properties."""
    rr = rerun_module()
    for i, mesh in enumerate(value.meshes):
        parts = entity_parts(mesh.name) or [f"mesh_{i:04d}"]
        child = log.child("/".join(parts))
        log_value(mesh, child)
        material = value.materials[value.material_of[i]]
        child.log("", rr.AnyValues(kind=parts[0], material=material.name), static=True)
