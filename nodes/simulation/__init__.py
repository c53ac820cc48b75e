"""XPBD aggregate simulation — SPEC §3 (G §3.3) and §5 (shape matching).

``xpbd`` is the node (thin declaration, imported here for the registry; it imports only numpy and
nodegraph at top level); each constraint family has its own numba kernel module
(``shape_matching``, ``contact_constraints``, ``friction``, ``adhesion``, ``collider``,
``buoyancy``), driven substep by substep by ``solver``, which runs only the requested effects.
The kernels are imported when the node runs, so listing nodes stays cheap.
"""

from .xpbd import xpbd

__all__ = ["xpbd"]
