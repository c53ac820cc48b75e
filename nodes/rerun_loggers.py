"""How the built-in value types appear in Rerun: registered on the engine's ``log_value`` dispatch.

Element libraries laid out in a row, sphere sets and volume cells as points, placements as points and
normals, aggregates as instanced library meshes, particles as points, shaded scenes as one mesh per element part
and material (SPEC §1–4 outputs).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nodegraph.context import EntityLogger
from nodegraph.rerun_log import log_value, mesh_colors, rerun_module

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


def scene_groups(value: ShadedScene) -> dict[str, list[int]]:
    """The scene's meshes by entity path below the scene: their names without the element numbers
    (``japonica/0012`` → ``japonica``, ``ikura/0003/yolk`` → ``ikura/yolk``, ``bowl_container``), and, where
    meshes of one path have several materials (ice by syrup grade), the material's name below it. In order
    of first appearance."""
    paths = [
        "/".join(p for p in entity_parts(mesh.name) if not p.isdigit()) or f"mesh_{i:04d}"
        for i, mesh in enumerate(value.meshes)
    ]
    materials: dict[str, set[int]] = {}
    for path, k in zip(paths, value.material_of):
        materials.setdefault(path, set()).add(int(k))
    groups: dict[str, list[int]] = {}
    for i, (path, k) in enumerate(zip(paths, value.material_of)):
        if len(materials[path]) > 1:
            path = f"{path}/{'_'.join(entity_parts(value.materials[k].name)) or f'material_{k}'}"
        groups.setdefault(path, []).append(i)
    return groups


@log_value.register
def _(value: ShadedScene, log: EntityLogger) -> None:
    """The final meshes once, one ``Mesh3D`` per element part and material (``scene_groups``), with its kind,
    material and number of meshes as properties. A mesh per element (1,112 in the main job) made the recording
    slow to write (1.6 s against 0.3 s) and gave the viewer a thousand entities to open."""
    rr = rerun_module()
    for path, members in scene_groups(value).items():
        meshes = [value.meshes[i] for i in members]
        starts = np.cumsum([0] + [len(m.vertices) for m in meshes])
        normals = None if any(m.normals is None for m in meshes) else np.concatenate([m.normals for m in meshes])
        colors = [mesh_colors(m) for m in meshes]
        if all(c is not None for c in colors) and len({c.shape[1] for c in colors}) > 1:  # RGB beside RGBA
            colors = [c if c.shape[1] == 4 else np.column_stack([c, np.full(len(c), 255, np.uint8)]) for c in colors]
        material = value.materials[value.material_of[members[0]]]
        child = log.child(path)
        child.log(
            "",
            rr.Mesh3D(
                vertex_positions=np.concatenate([m.vertices for m in meshes]).astype(np.float32),
                triangle_indices=np.concatenate([m.faces + s for m, s in zip(meshes, starts)]).astype(np.uint32),
                vertex_normals=None if normals is None else normals.astype(np.float32),
                vertex_colors=None if any(c is None for c in colors) else np.concatenate(colors),
            ),
            static=True,
        )
        child.log("", rr.AnyValues(kind=path.split("/")[0], material=material.name, meshes=len(meshes)), static=True)
