"""Export and preview — SPEC §4 outputs: ``export`` (glTF binary with KHR_materials_*, USD with
UsdPreviewSurface, PLY, OBJ, all as bytes) and ``preview`` (a Mitsuba 3 path-traced PNG).
Writers: ``gltf_writer``, ``usd_writer``, ``mesh_files``; renderer setup: ``mitsuba_scene``.
"""

from .export import export
from .preview import preview

__all__ = ["export", "preview"]
