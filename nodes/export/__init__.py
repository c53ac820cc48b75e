"""Export and preview — SPEC §4 outputs: ``export`` (glTF binary with KHR_materials_*, USD with
UsdPreviewSurface, PLY, OBJ, all as bytes), ``preview`` (a Mitsuba 3 path-traced, OIDN-denoised PNG) and
``image_grid`` (previews side by side, e.g. a water-content series).
Writers: ``gltf_writer``, ``usd_writer``, ``mesh_files``; renderer setup: ``mitsuba_scene``.
"""

from .export import export
from .image_grid import image_grid
from .preview import preview

__all__ = ["export", "image_grid", "preview"]
