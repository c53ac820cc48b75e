"""Node ``rice_variety``: one rice variety preset, read by every node that depends on it — SPEC §1.1 (G §3.1.1).

The variety is stated once: ``base_mesh`` takes its length factor, ``expand`` its P (when wired), the
``element_library`` its name as the element kind, and ``cooked_rice`` its name.
"""

from __future__ import annotations

from nodegraph import Out, Param, node

from ..values import RiceVariety
from .grain_shapes import RICE_VARIETIES


@node(
    "rice_variety",
    outputs={"variety": Out(RiceVariety, "the variety: name (the library's element kind), length factor, P")},
    params={
        "variety": Param(
            str,
            "japonica",
            "rice variety: length factor / expansion P (indica 1.8 / 1.2, japonica 1.0 / 1.5, aromatic 0.7 / 1.5)",
            choices=tuple(RICE_VARIETIES),
        )
    },
)
def rice_variety(ctx, *, variety):
    """A rice variety preset (SPEC §1.1), read by base_mesh, expand, element_library and cooked_rice."""
    return RICE_VARIETIES[variety]
