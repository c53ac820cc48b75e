"""XPBD aggregate simulation — SPEC §3 (G §3.3) and §5 (shape matching).

``xpbd`` is the node (thin declaration, imported here for the registry; it imports only numpy,
nodegraph and ``settings`` at top level). ``settings`` holds the effects, the node's typed
parameters and the solver settings; ``model`` what a run does not change, ``state`` what each
substep changes, ``buffers`` the kernels' scratch. Each constraint family has its own numba kernel
module (``shape_matching``, ``contact_constraints``, ``friction``, ``adhesion``, ``collider``,
``buoyancy``, ``bending``), driven substep by substep by ``solver``, which runs only the requested
effects. The kernels are imported when the node runs, so listing nodes stays cheap.
"""

from .xpbd import xpbd

__all__ = ["xpbd"]
