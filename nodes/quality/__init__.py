"""Quality of a result, measured on the exported element meshes, not on the simulation particles
(SPEC §2.7, §3): interpenetration between neighbours, packing, contacts, fill height.

``measure`` is the node; ``mesh_overlap`` holds the pure functions the tests and benchmarks call.
"""

from .measure import measure

__all__ = ["measure"]
