"""XPBD aggregate simulation — SPEC §3 (G §3.3) and §5 (shape matching).

``xpbd`` is the node (thin declaration); each constraint family has its own numba kernel module
(``shape_matching``, ``contact_constraints``, ``friction``, ``adhesion``, ``collider``,
``buoyancy``), driven substep by substep by ``solver``, which runs only the requested effects.
"""
