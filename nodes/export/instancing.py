"""Which exported meshes are one mesh moved rigidly: the groups the writers instance (USD ``PointInstancer``,
glTF nodes sharing one mesh) instead of writing each copy's vertices.

Decided per mesh from its vertices, not from the recipe: a mesh joins a group when it has the group's faces,
parts and material and its vertices (and normals) equal the group's prototype under a rotation and a translation
(Kabsch fit, residual within ``TOLERANCE``). An element dented by contact, shape-matched or bent fails the fit
and is written as its own mesh; an element that left the library unchanged (only placed) passes.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..values import ShadedScene

TOLERANCE = 1e-4  # mm: a tenth of a micrometre, a few float32 steps at a 100 mm scene; contact dents are ≥ 10 µm


@dataclass(frozen=True)
class InstanceGroup:
    """Meshes ``members`` (indices into the scene) that are the prototype — ``members[0]``'s mesh minus its
    centroid ``centre`` — rotated by ``rotations[k]`` and moved to ``positions[k]``: v = R·(p − centre) + t."""

    members: np.ndarray
    centre: np.ndarray
    rotations: np.ndarray
    positions: np.ndarray

    def quaternions(self) -> np.ndarray:
        """(k, 4) unit quaternions (x, y, z, w) of the rotations, w ≥ 0."""
        return rotation_quaternions(self.rotations)


def rotation_quaternions(rotations: np.ndarray) -> np.ndarray:
    """(k, 4) unit quaternions (x, y, z, w), w ≥ 0, of (k, 3, 3) rotation matrices."""
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(np.asarray(rotations, np.float64)).as_quat()
    q[q[:, 3] < 0] *= -1.0
    return q


def rigid_fit(prototype: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, float]:
    """The rotation R (no reflection) best mapping centred ``prototype`` onto centred ``points`` (Kabsch), and
    the largest vertex distance left, max ‖R·p − q‖."""
    h = prototype.T @ points
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    rotation = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    residual = np.linalg.norm(prototype @ rotation.T - points, axis=1).max()
    return rotation, float(residual)


class _Signatures:
    """The prototypes' signatures of one bucket, rows of a buffer that grows by doubling (not a stack of every
    row per mesh: a scene of dented grains has a prototype per grain)."""

    def __init__(self, width: int):
        self.rows = np.empty((4, width))
        self.count = 0

    def append(self, signature: np.ndarray) -> None:
        if self.count == len(self.rows):
            self.rows = np.concatenate([self.rows, np.empty_like(self.rows)])
        self.rows[self.count] = signature
        self.count += 1

    def near(self, signature: np.ndarray, tolerance: float) -> np.ndarray:
        """Indices (ascending) of the rows within ``tolerance`` of ``signature`` at every vertex: the rows whose
        first few vertices are, checked in full."""
        rows = self.rows[: self.count]
        head = min(8, len(signature))
        maybe = np.flatnonzero(np.abs(rows[:, :head] - signature[:head]).max(axis=1) <= tolerance)
        return maybe[np.abs(rows[maybe] - signature).max(axis=1) <= tolerance]


def instance_groups(scene: ShadedScene, tolerance: float = TOLERANCE) -> list[InstanceGroup]:
    """The groups of two or more meshes with faces that are one mesh under rigid motions, in scene order;
    meshes in no group are written as they are. Candidates are first narrowed by each vertex's distance from
    the centroid (unchanged by a rigid motion), then confirmed by ``rigid_fit`` on vertices and normals."""
    buckets: dict[tuple, list[list[int]]] = {}  # same material, faces, parts → prototypes, each with members
    signatures: dict[tuple, _Signatures] = {}
    fits: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # mesh → (rotation, centroid)
    digests: dict[tuple[int, int], str] = {}  # faces and parts arrays → their hash (a library mesh's are shared)
    for index, mesh in enumerate(scene.meshes):
        if len(mesh.faces) == 0:
            continue
        arrays = (id(mesh.faces), id(mesh.parts))
        if arrays not in digests:
            parts = b"" if mesh.parts is None else mesh.parts.tobytes()
            digests[arrays] = hashlib.sha1(mesh.faces.tobytes() + parts).hexdigest()
        key = (int(scene.material_of[index]), len(mesh.vertices), mesh.normals is None, digests[arrays])
        centre = mesh.vertices.mean(axis=0)
        local = mesh.vertices - centre
        signature = np.linalg.norm(local, axis=1)
        groups = buckets.setdefault(key, [])
        seen = signatures.setdefault(key, _Signatures(len(signature)))
        joined = False
        for g in seen.near(signature, tolerance):
            first = scene.meshes[groups[g][0]]
            rotation, residual = rigid_fit(first.vertices - fits[groups[g][0]][1], local)
            if residual > tolerance:
                continue
            if mesh.normals is not None and np.abs(first.normals @ rotation.T - mesh.normals).max() > 1e-4:
                continue
            groups[g].append(index)
            fits[index] = (rotation, centre)
            joined = True
            break
        if not joined:
            groups.append([index])
            seen.append(signature)
            fits[index] = (np.eye(3), centre)
    out = []
    for groups in buckets.values():
        for members in groups:
            if len(members) < 2:
                continue
            out.append(
                InstanceGroup(
                    members=np.asarray(members),
                    centre=fits[members[0]][1],
                    rotations=np.stack([fits[m][0] for m in members]),
                    positions=np.stack([fits[m][1] for m in members]),
                )
            )
    return sorted(out, key=lambda g: int(g.members[0]))


class WrittenMeshes(NamedTuple):
    """What a writer (.glb, USD) writes of a scene: the meshes with faces that are not copies of an instance
    group's prototype, their float32 positions (a prototype's centred on its group) and each one's bounds."""

    prototypes: dict[int, InstanceGroup]  # by the group's first member, the mesh written as its prototype
    indices: list[int]
    positions: list[np.ndarray]  # float32
    lows: np.ndarray  # (len(indices), 3) float32
    highs: np.ndarray


def written_meshes(scene: ShadedScene, instancing: bool, groups: list[InstanceGroup] | None = None) -> WrittenMeshes:
    """The meshes to write with ``instancing`` (``groups``: the scene's ``instance_groups`` when already found), as
    float32 in one conversion and one min/max reduction over all of them, not two per mesh."""
    found = (instance_groups(scene) if groups is None else groups) if instancing else []
    prototypes = {int(group.members[0]): group for group in found}
    copies = {int(k) for group in found for k in group.members[1:]}
    indices = [k for k, mesh in enumerate(scene.meshes) if len(mesh.faces) and k not in copies]
    if not indices:
        empty = np.empty((0, 3), np.float32)
        return WrittenMeshes(prototypes, indices, [], empty, empty)
    blocks = [
        scene.meshes[k].vertices - prototypes[k].centre if k in prototypes else scene.meshes[k].vertices
        for k in indices
    ]
    rows = np.asarray(np.concatenate(blocks), np.float32)
    starts = np.cumsum([0] + [len(b) for b in blocks[:-1]]).astype(np.int64)
    return WrittenMeshes(
        prototypes,
        indices,
        np.split(rows, starts[1:]),
        np.minimum.reduceat(rows, starts, axis=0),
        np.maximum.reduceat(rows, starts, axis=0),
    )
