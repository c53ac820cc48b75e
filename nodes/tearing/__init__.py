"""Elastic bodies that tear — SPEC §5 (U): ``surface_mesh`` (half-edge arrays that split along edges),
``tearing`` (break rules, clusters of the split mesh), ``body`` (U's shape-matching integration, one
cluster per piece, on the xpbd node's goal maps), and the ``elastic_body`` node (imported here for the
registry; it imports numpy and nodegraph only at top level).
"""

from .elastic_body import elastic_body

__all__ = ["elastic_body"]
