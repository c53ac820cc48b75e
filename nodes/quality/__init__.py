"""Quality of a result, measured on the exported element meshes, not on the simulation particles
(SPEC §2.7, §3): interpenetration between neighbours, packing, contacts, fill height.

``measure`` is the node (``mesh_overlap`` holds its pure functions); ``particle_contacts`` reads the
same qualities cheaply from the simulation particles (residual overlap, height, speed) for sweeps.
"""

from .measure import measure
from .particle_contacts import particle_contacts

__all__ = ["measure", "particle_contacts"]
