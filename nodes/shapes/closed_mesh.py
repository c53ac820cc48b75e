"""Checks and repairs that make a target shape a closed, outward-facing solid — SPEC §2 ("shape mesh (closed)")."""

from __future__ import annotations

import numpy as np
import trimesh

from ..mesh_io import read_mesh


def load_mesh(path: str, changes: list[str] | None = None) -> trimesh.Trimesh:
    """Read one triangle mesh (scenes are concatenated); a clear error naming the cause otherwise. ``changes``:
    what reading it changed is appended (duplicate vertices merged; not said of an STL, which stores each
    triangle's corners apart)."""
    try:
        mesh = read_mesh(path, process=False)
    except ValueError as exc:
        raise ValueError(f"path: {exc}") from exc
    given = len(mesh.vertices)
    mesh.process()
    if changes is not None and given > len(mesh.vertices) and not str(path).lower().endswith(".stl"):
        changes.append(f"merged {given - len(mesh.vertices):,} duplicate vertices")
    return mesh


def closed_mesh(mesh: trimesh.Trimesh, *, repair: bool, what: str, changes: list[str] | None = None) -> trimesh.Trimesh:
    """``mesh`` as a watertight solid with outward normals.

    With ``repair``: consistent winding, inverted orientation flipped, small holes filled
    (trimesh.repair). A mesh still open afterwards is refused: the aggregate needs an inside. ``changes``: what
    was changed is appended, in words (a user is told: ``Context.warn``).
    """
    changes = [] if changes is None else changes
    given = mesh
    mesh = mesh.copy()
    mesh.merge_vertices()
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.remove_unreferenced_vertices()
    if not mesh.is_watertight and given.is_watertight:  # merging near-coincident vertices at slivers opened it
        mesh = given.copy()
    elif len(mesh.faces) < len(given.faces):
        changes.append(f"dropped {len(given.faces) - len(mesh.faces):,} degenerate faces")
    if repair:
        faces, count = mesh.faces.copy(), len(mesh.faces)
        trimesh.repair.fix_winding(mesh)
        flipped = int((mesh.faces != faces).any(axis=1).sum()) if len(mesh.faces) == count else 0
        if flipped:
            changes.append(f"turned {flipped:,} faces to agree with their neighbours")
        trimesh.repair.fill_holes(mesh)
        if len(mesh.faces) > count:
            changes.append(f"filled holes ({len(mesh.faces) - count:,} face(s) added)")
        if mesh.is_watertight and mesh.volume < 0:
            changes.append("turned its normals outwards (it was inside out)")
        trimesh.repair.fix_inversion(mesh)
    if not mesh.is_watertight:
        fix = (
            "repair (on) could not close them: close the mesh in a modeller"
            if repair
            else "close it in a modeller, or pass repair: true for small holes"
        )
        raise ValueError(f"{what}: the mesh has holes (not watertight); {fix}")
    if mesh.volume < 0:
        if not repair:
            raise ValueError(f"{what}: normals point inwards (negative volume); pass repair: true to flip them")
        mesh.invert()
        changes.append("turned its normals outwards (it was inside out)")
    if not np.isfinite(mesh.vertices).all() or mesh.volume <= 0:
        raise ValueError(f"{what}: the mesh encloses no volume")
    return mesh


def as_trimesh(mesh, what: str) -> trimesh.Trimesh:
    """A nodegraph Mesh (or trimesh) checked as a closed solid without repairing it."""
    tm = mesh if isinstance(mesh, trimesh.Trimesh) else trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    return closed_mesh(tm, repair=False, what=what)
