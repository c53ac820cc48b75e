"""Target shapes of an aggregate — SPEC §2 inputs: primitives and bowls (``shape``), user meshes
(``mesh_file``) and manifold3d booleans (``boolean``). Kernels: ``solids``, ``closed_mesh``.
"""

from .boolean import boolean
from .mesh_file import mesh_file
from .shape import shape

__all__ = ["boolean", "mesh_file", "shape"]
