"""An aggregate whose elements may carry a displaced inner part (the ikura yolk) and flattened contacts —
SPEC §1, §3.

``Aggregate.element_mesh`` applies one map per element (affine, plus the quadratic bend when the
solver ran the quadratic goal); a yolk that rose inside its egg needs a second translation for the
faces of ``parts == 1``, added on top of that map; a grain flattened where it presses on its neighbours
(``contact_flattening``) moves some of its vertices on top of that, and their normals follow the new
surface. Subclass, not an edit of values.py.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from nodegraph.values import Mesh

from ..values import Aggregate


@dataclass(frozen=True, eq=False)
class DeformedAggregate(Aggregate):
    """``part_offsets[i]`` (world frame, length units) moves the vertices of element i's part-1 faces;
    rows k of ``dent_element`` / ``dent_vertex`` / ``dent_offset`` (sorted by element) move vertex
    ``dent_vertex[k]`` of element ``dent_element[k]`` by ``dent_offset[k]`` (world frame)."""

    part_offsets: np.ndarray | None = None
    dent_element: np.ndarray | None = None
    dent_vertex: np.ndarray | None = None
    dent_offset: np.ndarray | None = None

    @property
    def dented(self) -> bool:
        return self.dent_element is not None and len(self.dent_element) > 0

    def element_mesh(self, i: int) -> Mesh:
        mesh = super().element_mesh(i)
        moved_part = self.part_offsets is not None and mesh.parts is not None and np.any(mesh.parts == 1)
        rows = slice(0, 0)
        if self.dented:
            rows = slice(*np.searchsorted(self.dent_element, [i, i + 1]))
        if not moved_part and rows.start == rows.stop:
            return mesh
        vertices = mesh.vertices.copy()
        if moved_part:
            vertices[np.unique(mesh.faces[mesh.parts == 1])] += self.part_offsets[i]
        normals = mesh.normals
        if rows.start != rows.stop:
            dent = self.dent_vertex[rows]
            vertices[dent] += self.dent_offset[rows]
            if normals is not None:
                normals = _renormalised(vertices, mesh.faces, normals, dent)
        return Mesh(vertices, mesh.faces, normals=normals, parts=mesh.parts, name=mesh.name)

    def subset(self, keep: np.ndarray) -> DeformedAggregate:
        """The elements of a boolean mask, with their deformations, part offsets and dents."""
        per_element = {
            name: getattr(self, name)[keep]
            for name in ("deformations", "bends", "part_offsets")
            if getattr(self, name) is not None
        }
        if self.dented:
            index = np.cumsum(keep) - 1
            rows = keep[self.dent_element]
            per_element |= {
                "dent_element": index[self.dent_element[rows]],
                "dent_vertex": self.dent_vertex[rows],
                "dent_offset": self.dent_offset[rows],
            }
        return dataclasses.replace(self, placement=self.placement.subset(keep), **per_element)


def _renormalised(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray, moved: np.ndarray) -> np.ndarray:
    """``normals`` with the moved vertices' replaced by the area-weighted normal of their faces as they are
    now (a flattened patch shades flat); the others keep theirs."""
    touched = np.zeros(len(vertices), bool)
    touched[moved] = True
    near = faces[touched[faces].any(axis=1)]
    a, b, c = (vertices[near[:, k]] for k in range(3))
    face_normal = np.cross(b - a, c - a)  # length = 2 × area: area-weighted
    summed = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(summed, near[:, k], face_normal)
    out = np.array(normals, np.float64, copy=True)
    length = np.linalg.norm(summed[moved], axis=1, keepdims=True)
    ok = length[:, 0] > 0
    out[moved[ok]] = summed[moved[ok]] / length[ok]
    return out
