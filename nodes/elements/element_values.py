"""Value types the element chain adds to ``nodegraph.values`` (subclasses, so ports stay typed).

A grain's expansion P (G eq. 6) is drawn in ``expand`` but needed by ``element_library``; it rides
along on the field and then on the mesh instead of a side channel.
"""

from __future__ import annotations

from dataclasses import dataclass

from nodegraph.values import Mesh

from ..values import DistanceField


@dataclass(frozen=True, eq=False)
class ExpandedField(DistanceField):
    """A distance field after expansion by ``expansion`` = P (G eq. 6)."""

    expansion: float = 1.0


@dataclass(frozen=True, eq=False)
class GrainMesh(Mesh):
    """A remeshed element: watertight, outward, centred at its volume centroid, in mm.

    ``expansion`` is the P it was grown by; ``inradius`` the radius of the largest inscribed
    sphere (the field's maximum), which placement uses to size its Poisson radius (SPEC §2.2).
    """

    expansion: float = 1.0
    inradius: float = 0.0
