"""Target shapes of an aggregate — SPEC §2 inputs: primitives and bowls (``shape``), regions derived from a
bowl (``vessel_region``), user meshes (``mesh_file``) and manifold3d booleans (``boolean``); a topping slab
draped over an aggregate (``drape``: the fish on nigiri); a nori band round a shape's
bottom (``nori``); a plate under a shape, sized by it (``plate``); chopsticks on the table beside a dish
(``chopsticks``).
Kernels: ``solids``, ``closed_mesh``, ``plate_drape``.
"""

from .boolean import boolean
from .chopsticks import chopsticks
from .drape import drape
from .mesh_file import mesh_file
from .nori import nori
from .plate import plate
from .shape import shape
from .vessel_region import vessel_region

__all__ = ["boolean", "chopsticks", "drape", "mesh_file", "nori", "plate", "shape", "vessel_region"]
