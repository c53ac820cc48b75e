"""Aperiodic space filling — SPEC §2 (S §3, G §3.2.2):
poisson_place → rotate → mix_ratio → (medial_spheres) → overlap_refine → cull, or → lift_apart (round elements
of different sizes: each lifted clear of those below it by its own size); ``cut`` removes a
half-space or a ball from a result so a volume fill's inside shows (G's cut rice bunny).

Declaration modules (one node each, imported here for the registry) import only numpy and
nodegraph at top level; the kernels (``candidates``, ``dart_throw``, ``frames``,
``medial_spheres``, ``element_templates``, ``refine``, ``refine_kernels``) are imported when a node runs.
"""

from .cull import cull
from .cut import cut
from .implicit_function import carry_medial_spheres
from .lift_apart import lift_apart
from .mix_ratio import mix_ratio
from .overlap_refine import overlap_refine
from .poisson_place import poisson_place
from .rotate import rotate

__all__ = [
    "carry_medial_spheres",
    "cull",
    "cut",
    "lift_apart",
    "mix_ratio",
    "overlap_refine",
    "poisson_place",
    "rotate",
]
