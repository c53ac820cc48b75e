"""A user's element mesh from a file (SPEC §1.1: "any user mesh"), repaired or refused with a reason.

Documented repairs: duplicate vertices are merged, degenerate (zero-area) and duplicate faces are
dropped, an inside-out mesh is inverted, the mesh is moved to its volume centroid and (optionally)
turned so its principal axes are x ≥ y ≥ z in extent. Refused: unreadable file, non-finite
coordinates, no faces, not closed (holes or non-manifold edges), inconsistent orientation,
zero volume; ``nodegraph check`` reads the file and says the same before any work (``base_mesh``). trimesh is
imported inside the functions (node modules must import cheaply).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..mesh_io import read_mesh


class MeshFileError(ValueError):
    """A mesh file that cannot be used as an element, with the reason and what would be accepted."""


def load_element_mesh(
    path: str | Path, scale: float = 1.0, align: bool = True, changes: list[str] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (mm) and faces of a closed, outward, centred element mesh read from ``path``; ``changes``: the
    repairs made, in words, are appended (duplicate vertices merged: not said of an STL, which stores each
    triangle's corners apart)."""
    try:
        loaded = read_mesh(path, process=False)
    except ValueError as exc:
        raise MeshFileError(str(exc)) from exc
    vertices = np.asarray(getattr(loaded, "vertices", np.empty((0, 3))), dtype=np.float64)
    faces = np.asarray(getattr(loaded, "faces", np.empty((0, 3))), dtype=np.int64)
    made: list[str] = []
    out = repair_element_mesh(vertices * scale, faces, source=str(path), align=align, changes=made)
    if changes is not None:
        changes += [c for c in made if not (c.startswith("merged") and str(path).lower().endswith(".stl"))]
    return out


def repair_element_mesh(
    vertices: np.ndarray,
    faces: np.ndarray,
    source: str = "mesh",
    align: bool = True,
    changes: list[str] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Apply the documented repairs to a mesh, or raise MeshFileError saying why it cannot be used; ``changes``:
    each repair made is appended, in words."""
    import trimesh

    changes = [] if changes is None else changes

    if len(faces) == 0 or len(vertices) == 0:
        raise MeshFileError(f"{source}: no triangles found; an element needs a closed triangle mesh")
    if not np.isfinite(vertices).all():
        bad = int((~np.isfinite(vertices)).any(axis=1).sum())
        raise MeshFileError(f"{source}: {bad} vertices have NaN or infinite coordinates")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise MeshFileError(f"{source}: face indices out of range (0..{len(vertices) - 1})")
    mesh = trimesh.Trimesh(vertices, faces, process=True, validate=False)
    merged = len(vertices) - len(mesh.vertices)
    count = len(mesh.faces)
    mesh.update_faces(mesh.nondegenerate_faces())
    if len(mesh.faces) < count:
        changes.append(f"dropped {count - len(mesh.faces):,} degenerate faces")
    count = len(mesh.faces)
    mesh.update_faces(mesh.unique_faces())
    if len(mesh.faces) < count:
        changes.append(f"dropped {count - len(mesh.faces):,} duplicate faces")
    mesh.remove_unreferenced_vertices()
    if merged > 0:
        changes.insert(0, f"merged {merged:,} duplicate vertices")
    if len(mesh.faces) == 0:
        raise MeshFileError(f"{source}: every face is degenerate (zero area); nothing is left of the mesh")
    if not mesh.is_watertight:
        open_edges = len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
        raise MeshFileError(
            f"{source}: mesh is not closed ({open_edges} boundary edges, or edges shared by "
            "more than two faces); an element must be a closed (watertight) surface: fill its holes and export it "
            "again (Blender: Select All, then Mesh > Clean Up > Fill Holes; or trimesh: trimesh.repair.fill_holes)"
        )
    if not mesh.is_winding_consistent:
        raise MeshFileError(
            f"{source}: faces are not consistently oriented (some neighbours disagree); "
            "fix the winding or export with consistent normals"
        )
    scale = float(np.ptp(mesh.vertices, axis=0).max())
    if abs(mesh.volume) <= 1e-9 * scale**3:
        raise MeshFileError(f"{source}: mesh encloses zero volume (flat or collapsed); an element needs a solid")
    if mesh.volume < 0:
        mesh.invert()  # documented repair: inside-out mesh
        changes.append("turned its normals outwards (it was inside out)")
    vertices = mesh.vertices - mesh.center_mass
    if align:
        vertices = vertices @ principal_frame(vertices)
    return np.ascontiguousarray(vertices), np.asarray(mesh.faces, np.int64)


def principal_frame(vertices: np.ndarray) -> np.ndarray:
    """Rotation (columns = new x, y, z) onto the principal axes ordered by extent, det = +1.

    Axes come from the vertex covariance of the centred mesh; each axis's sign is chosen so the
    farthest vertex along it lies on the positive side, making the frame deterministic.
    """
    _, vectors = np.linalg.eigh(np.cov(vertices.T))
    vectors = vectors[:, ::-1]  # largest spread first: long axis = x
    for a in range(3):
        proj = vertices @ vectors[:, a]
        if abs(proj.min()) > abs(proj.max()):
            vectors[:, a] = -vectors[:, a]
    if np.linalg.det(vectors) < 0:
        vectors[:, 2] = -vectors[:, 2]
    return vectors
