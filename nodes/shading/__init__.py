"""Shading — SPEC §4 (G §3.1.2): water-content-aware CDRF vertex colours and principled materials.

``shade`` is the node (thin declaration); the kernels are ``cdrf`` (eq. 7–9: exact, quadrature,
fitted table), ``curvature`` (libigl mean curvature), ``vertex_shading`` (lights), ``materials``
(presets: rice by water content, ikura membrane/yolk, ice with syrup) and ``scene_shading``.
"""

from .shade import shade

__all__ = ["shade"]
