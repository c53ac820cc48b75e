"""The cooked material — SPEC §3–4: one node (``cooked_rice``) holds a rice's variety and water content and
derives what the simulation (moisture: stiffness, friction, adhesion) and the shading (CDRF σ₀, the
principled material) read from them, so the two cannot disagree. Kernel: ``cooked``.
"""

from .cooked_rice import cooked_rice

__all__ = ["cooked_rice"]
