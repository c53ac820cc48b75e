"""The ``drape`` node: a topping slab draped over an aggregate's top — the fish on nigiri (issue 17, a plus
beside G ch.4's sushi rice). The slab is a thin elastic plate resting on the rice's upper envelope under its
weight and the press of the hand (``plate_drape``); its faces are flesh or fat (``Mesh.parts``: 0, 1), which
``shade`` turns into the fish's two materials.
"""

from __future__ import annotations

import numpy as np

from nodegraph.node import In, Out, node
from nodegraph.params import Param

from ..values import Aggregate

FISH = ("salmon", "tuna")
# kind → (fat line spacing, line width, angle to the slab's width, chevron depth), mm and degrees
# (``plate_drape.fat_lines``; the mean width across the line: it swells and thins a little along its length):
# salmon shows thin pale chevrons a flake apart, tuna (akami) fainter, sparser ones
FAT_LINES = {"salmon": (6.0, 0.5, 45.0, 4.0), "tuna": (9.0, 0.5, 20.0, 3.0)}


@node(
    "drape",
    inputs={"aggregate": In(Aggregate, "the aggregate the slab rests on (its element meshes' top)")},
    outputs={"aggregate": Out(Aggregate, "the draped slab: one element of kind 'salmon' or 'tuna'")},
    params={
        "kind": Param(str, "salmon", "the fish (its element kind: the shade node's material preset)", choices=FISH),
        "size": Param(
            tuple[float, float, float],
            (64.0, 27.0, 5.0),
            "slab length, width and thickness before draping (a nigiri neta)",
            range=(0.1, 1e3),
            units="mm",
        ),
        "corner": Param(float, 8.0, "corner radius of the slab's outline", range=(0.0, 1e3), units="mm"),
        # An effective modulus: a raw slice pressed on by hand keeps the pressed form, so the drape is its
        # rest shape under the press; 1.5 kPa with the press below lets a 5 mm slab follow a nigiri's rounded
        # ends (stiffer slabs bridge them: try 20 for a slab that barely bends)
        "young_modulus": Param(
            float, 1.5, "slab stiffness E (bending stiffness D = E·t³/12)", range=(1e-3, 1e6), units="kPa"
        ),
        "density": Param(float, 1.05, "slab density (raw fish ≈ 1.05)", range=(0.1, 10.0), units="g/cm³"),
        "press": Param(float, 150.0, "pressure of the hand pressing the slab on", range=(0.0, 1e5), units="Pa"),
        "gravity": Param(float, 9810.0, "gravitational acceleration, along −z", range=(0.0, 1e5), units="mm/s²"),
        "yaw": Param(float, 0.0, "turn of the slab's length from +x about z", range=(-360.0, 360.0), units="degrees"),
        "offset": Param(
            tuple[float, float],
            (0.0, 0.0),
            "slab centre from the centre of the aggregate's footprint",
            range=(-1e4, 1e4),
            units="mm",
        ),
        "clearance": Param(float, 0.05, "gap kept above the aggregate's top", range=(0.0, 10.0), units="mm"),
        "cell": Param(
            float,
            0.5,
            "grid cell of the plate and largest cell of the slab's mesh (which is finer where needed: under half "
            "its fat lines' width)",
            range=(0.05, 10.0),
            units="mm",
        ),
    },
)
def drape(ctx, aggregate, *, kind, size, corner, young_modulus, density, press, gravity, yaw, offset, clearance, cell):
    """The slab's bottom on the plate's rest shape (Kirchhoff plate on the aggregate's upper envelope), its
    thickness along the normal, its length kept (arc length), its faces flesh or fat."""
    from nodegraph.values import Mesh

    from ..values import ElementLibrary, Placement
    from .plate_drape import (
        PlateGrid,
        drape_plate,
        drape_points,
        fat_lines,
        flake_relief,
        rounded_slab,
        upper_envelope,
    )

    length, width, thickness = size
    if thickness >= width or width > length:
        raise ValueError(f"size {list(size)}: expected length ≥ width > thickness (a slab)")
    n = len(aggregate.placement)
    if n == 0:
        raise ValueError("aggregate: empty; the slab needs something to rest on")
    points = np.concatenate([aggregate.element_mesh(i).vertices for i in range(n)])
    centre = 0.5 * (points[:, :2].min(axis=0) + points[:, :2].max(axis=0)) + np.asarray(offset)
    a = np.radians(yaw)
    axes = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])  # rows: u, v in world xy
    local = np.c_[(points[:, :2] - centre) @ axes.T, points[:, 2] + clearance]

    grid = PlateGrid.covering(length, width, cell)
    bending = young_modulus * thickness**3 / 12.0  # kPa·mm³
    load = density * 1e-6 * gravity * thickness + press * 1e-3  # kg/mm³·mm/s²·mm = kPa
    w = drape_plate(upper_envelope(local, grid), grid, bending, load)

    lines = FAT_LINES[kind]
    vertices, faces = rounded_slab(length, width, thickness, corner, min(cell, 0.5 * lines[1]))
    parts = fat_lines(vertices[faces].mean(axis=1), width, *lines)
    spacing, _, angle, chevron = lines
    vertices[:, 2] += flake_relief(vertices, thickness, width, spacing, angle, chevron)
    draped = drape_points(vertices, thickness, w, grid)
    world = np.c_[draped[:, :2] @ axes + centre, draped[:, 2]]
    middle = world.mean(axis=0)
    mesh = Mesh(world - middle, faces, parts=parts, name=kind)
    if ctx.rerun.enabled:
        import rerun as rr

        ctx.rerun.log("slab", rr.Mesh3D(vertex_positions=world, triangle_indices=faces))
    placement = Placement(middle[None], [[0.0, 0.0, 1.0]], kind_names=(kind,))
    return Aggregate(placement, (ElementLibrary(kind, (mesh,)),))
