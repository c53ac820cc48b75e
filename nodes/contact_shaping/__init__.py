"""Shaping the grains' meshes where they touch, after the physics — SPEC §3's soft grains at mesh resolution
(issues 17, 25): the simulation leaves sphere clusters that touch, and these steps make the exported meshes touch
without cutting into each other.

``deform_contacts`` dents each mesh smoothly where it presses and bulges it where it is free, keeping its volume
(kernels: ``contact_deformation``); ``flatten_contacts``, the earlier step, presses the meshes flat where they meet
(``contact_flattening``, which also gathers what both steps read: world vertices, neighbour lists, wall fields);
``cull_crossing`` removes the elements still cutting into a neighbour deeper than a threshold. The nodes are
imported here for the registry (numpy and nodegraph at top level); the kernels when a node runs.
"""

from .cull_crossing import cull_crossing
from .deform_contacts import deform_contacts
from .flatten_contacts import flatten_contacts

__all__ = ["cull_crossing", "deform_contacts", "flatten_contacts"]
