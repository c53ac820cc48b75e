"""Element modelling nodes — SPEC §1 (G §3.1.1): base mesh → sphere scatter → voxelise →
distance field → expand → remesh, gathered into an element library; a rice variety (``rice_variety``)
stated once and read by the base mesh, the expansion and the library.

Declaration modules (one node each, imported here for the registry) are thin and import only numpy
and nodegraph at top level; the kernels (``grain_shapes``, ``sphere_sampling``, ``voxel_grid``,
``grid_kernels``, ``distance_fields``, ``level_set_mesh``, ``library_props``, ``mesh_files``) hold
the pure functions tests call and are imported only when a node runs.
"""

from .base_mesh import base_mesh
from .distance_field import distance_field
from .element_library import element_library
from .expand import expand
from .remesh import remesh
from .rice_variety import rice_variety
from .sphere_scatter import sphere_scatter
from .voxelise import voxelise

__all__ = [
    "base_mesh",
    "distance_field",
    "element_library",
    "expand",
    "remesh",
    "rice_variety",
    "sphere_scatter",
    "voxelise",
]
