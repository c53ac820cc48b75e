"""An aggregate whose elements may carry a displaced inner part (the ikura yolk) — SPEC §1, §3.

``Aggregate.element_mesh`` applies one map per element (affine, plus the quadratic bend when the
solver ran the quadratic goal); a yolk that rose inside its egg needs a second translation for the
faces of ``parts == 1``, added on top of that map. Subclass, not an edit of values.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nodegraph.values import Mesh

from ..values import Aggregate


@dataclass(frozen=True, eq=False)
class DeformedAggregate(Aggregate):
    """``part_offsets[i]`` (world frame, length units) moves the vertices of element i's part-1 faces."""

    part_offsets: np.ndarray | None = None

    def element_mesh(self, i: int) -> Mesh:
        mesh = super().element_mesh(i)
        if self.part_offsets is None or mesh.parts is None or not np.any(mesh.parts == 1):
            return mesh
        vertices = mesh.vertices.copy()
        moved = np.unique(mesh.faces[mesh.parts == 1])
        vertices[moved] += self.part_offsets[i]
        return Mesh(vertices, mesh.faces, normals=mesh.normals, parts=mesh.parts, name=mesh.name)
