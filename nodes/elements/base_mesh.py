"""Node ``base_mesh``: the low-resolution element model — SPEC §1.1 (G §3.1.1, G eq. 10)."""

from __future__ import annotations

import numpy as np

from nodegraph import In, Moved, Out, Param, node
from nodegraph.cost import Cost, CostQuery, estimated_by
from nodegraph.node import warns_of
from nodegraph.values import Mesh

from ..values import RiceVariety
from . import grain_shapes
from .element_room import element_fits
from .grain_shapes import DEFAULT_SIZE, RICE_VARIETIES

SHAPES = ("rice", "ikura", "ice_flake", "chestnut", "file")


def _check(p: dict) -> list[tuple[str, str]]:
    issues = []
    if p["shape"] == "file" and not p["path"]:
        issues.append(("path", "shape 'file' needs a path to a mesh file"))
    if p["shape"] == "file" and p["path"]:
        from ..mesh_io import file_problem

        problem = file_problem(p["path"])
        if problem is None:  # read and repaired as the run would (the bunny: ≈ 0.1 s): one not closed is refused now
            from .mesh_files import MeshFileError, load_element_mesh

            try:
                load_element_mesh(p["path"], p["scale"], align=False)
            except MeshFileError as exc:
                problem = str(exc)
        if problem is not None:
            issues.append(("path", problem))
    if p["shape"] != "file" and p["path"]:
        issues.append(("path", f"path is only used with shape 'file' (shape is '{p['shape']}')"))
    if p["shape"] != "ice_flake" and p["curl"]:
        issues.append(("curl", f"curl is only used with shape 'ice_flake' (shape is '{p['shape']}')"))
    if p["shape"] != "ikura" and p["diameter_sd"]:
        issues.append(("diameter_sd", f"diameter_sd is only used with shape 'ikura' (shape is '{p['shape']}')"))
    if p["diameter_sd"] > 0.25 * p["diameter"]:
        issues.append(
            (
                "diameter_sd",
                f"{p['diameter_sd']:g} mm is over a quarter of the diameter {p['diameter']:g} mm; allowed: "
                f"diameter_sd ≤ {0.25 * p['diameter']:g} mm (draws are clipped at ±2 sd, so an egg keeps at least "
                "half the mean diameter)",
            )
        )
    if p["shape"] == "ikura" and p["eye_gap"] > 0:
        r_i = (p["diameter"] - 2 * p["diameter_sd"]) / 2  # the smallest egg a variant draws (±2 sd)
        room = 1 - p["lipid_fraction"] ** (1 / 3)  # the membrane's radius less the yolk's, per mm of radius
        free = r_i * room
        if free <= 0:  # no eye_gap fits: the diameter is what leaves none, named with the diameters that fit
            least = 2 * p["diameter_sd"] + 2 * p["eye_gap"] / room
            issues.append(
                (
                    "diameter",
                    f"{p['diameter']:g} mm leaves the smallest egg (at −2 sd: {p['diameter']:g} − 2 × diameter_sd "
                    f"{p['diameter_sd']:g} mm) no radius, so no room for the yolk's eye_gap {p['eye_gap']:g} mm: "
                    f"allowed: diameter > {least:.3g} mm (or a smaller diameter_sd)",
                )
            )
        elif p["eye_gap"] >= free:
            issues.append(
                (
                    "eye_gap",
                    f"{p['eye_gap']:g} mm leaves the yolk no room to move up: allowed 0 ≤ eye_gap < {free:.3g} mm "
                    "(the membrane's radius less the yolk's, on the smallest egg)",
                )
            )
    if p["shape"] in ("ikura", "file") and p["size"] is not None:
        issues.append(("size", f"size is not used by shape '{p['shape']}' (ikura: diameter; file: scale)"))
    return issues


def _cost(q: CostQuery) -> Cost:
    """The smallest inscribed radius its meshes can have and their volume (what a placement whose r comes from the
    elements reads), from the parameters alone: an egg's radius at its diameter's low clip (−2 sd) and the volume
    at its mean diameter, a grain's or flake's half thickness, a grain's volume its mesh's at the wired variety's
    length (made now: milliseconds), its length over its width (a slender run's clusters); and its faces; a file's
    are not known before it is read."""
    p = q.params
    sphere = 20 * 4 ** p["subdivisions"]  # faces of the icosphere a grain or an egg's shell is made from
    if p["shape"] == "ikura":  # membrane and yolk, each a sphere one subdivision finer
        volume = np.pi / 6.0 * p["diameter"] ** 3
        return Cost(inscribed=0.5 * (p["diameter"] - 2.0 * p["diameter_sd"]), volume=volume, faces=2 * 4 * sphere)
    if p["shape"] == "file":
        return Cost()
    size = p["size"] or DEFAULT_SIZE[p["shape"]]
    if p["shape"] == "chestnut":  # a quarter of the kernel: about half its smallest half-size
        return Cost(inscribed=0.25 * min(size), faces=sphere)
    if p["shape"] != "rice":
        longest, middle, _ = sorted(size, reverse=True)
        return Cost(inscribed=0.5 * min(size), elongation=longest / middle, faces=sphere)
    factor = _length_factor(q)
    if factor is None:
        return Cost(inscribed=0.5 * min(size), faces=sphere)
    length, width, thickness = size
    mesh = grain_shapes.rice_grain(length * factor, width, thickness, p["bluntness"], p["bend"], p["subdivisions"])
    volume = grain_shapes.volume_centroid(*mesh)[0]
    return Cost(inscribed=0.5 * min(size), volume=volume, elongation=length * factor / width, faces=sphere)


def _length_factor(q: CostQuery) -> float | None:
    """The length factor of the variety wired from a rice_variety node (1 unwired; None when a variety comes from
    elsewhere)."""
    wires = q.nodes[q.node_id].inputs.get("variety") or []
    if not wires:
        return 1.0
    source = q.nodes.get(wires[0].node)
    if source is None or source.spec.type_name != "rice_variety":
        return None
    return RICE_VARIETIES[source.params["variety"]].length_factor


def _warns(node_id: str, nodes) -> list[tuple[str, str]]:
    """What a run will say of the element's mesh file (``nodegraph check``): its repairs; nothing for another shape
    or a file that cannot be used (the parameter's own check says why)."""
    from ..mesh_io import repair_line
    from .mesh_files import MeshFileError, load_element_mesh

    params = nodes[node_id].params
    if params["shape"] != "file" or not params["path"]:
        return []
    changes: list[str] = []
    try:
        load_element_mesh(params["path"], params["scale"], align=False, changes=changes)
    except (MeshFileError, ValueError):
        return []
    return [("path", repair_line(params["path"], changes))] if changes else []


@warns_of(_warns)
@estimated_by(_cost)
@node(
    "base_mesh",
    inputs={
        "variety": In(
            RiceVariety,
            "rice: the variety whose length factor multiplies size[0] (SPEC §1.1); unwired: factor 1",
            optional=True,
        )
    },
    outputs={"mesh": Out(Mesh, "closed outward element mesh, centred, long axis x, mm")},
    params={
        "shape": Param(str, "rice", "which base model", choices=SHAPES),
        "size": Param(
            tuple[float, float, float],
            None,
            "length, width, thickness before the variety factor; default rice 5.2×3.0×2.0 (a raw Japanese short "
            "grain, docs/sizes.md), ice flake 4×3×0.4; chestnut: the whole peeled kernel before it is cut, "
            "default 26×23×17",
            range=(0.01, 1000.0),
            units="mm",
            nullable=True,
        ),
        "bluntness": Param(float, 0.8, "rice: end shape exponent (1 = ellipsoid, smaller = blunter)", range=(0.3, 1.0)),
        "bend": Param(
            float, 0.05, "rice: dorsal bend, y offset at the tips as a fraction of the width", range=(0.0, 0.5)
        ),
        "diameter": Param(
            float,
            6.5,
            "ikura: mean egg diameter 2·r_i (salted chum roe 6–7 mm, docs/sizes.md)",
            range=(0.1, 100.0),
            units="mm",
        ),
        "diameter_sd": Param(
            float,
            0.0,
            "ikura: standard deviation of the diameter between eggs (each variant draws its own, clipped at ±2 sd); "
            "0: every egg alike",
            range=(0.0, 25.0),
            units="mm",
        ),
        # default: typical ikura lipid mass fraction, SPEC §1 (Shirai et al.): 14.5 ± 0.7 %
        "lipid_fraction": Param(
            float,
            0.145,
            "ikura: lipid (yolk) fraction L; yolk radius r_o = r_i·∛L (G eq. 10, SPEC Reading)",
            range=(0.001, 0.95),
        ),
        # the egg's oil (its yolk here, G eq. 10), lighter than the fluid, floats up against the membrane: what a
        # photograph shows as each egg's pale eye (docs/look.md, "Ikura colour")
        "eye_gap": Param(
            float,
            0.15,
            "ikura: the yolk (oil droplet) sits off-centre, along the egg's own +z, its surface this far under the "
            "membrane (the pale eye seen through the thin fluid over it); 0: concentric, as G eq. 10",
            range=(0.0, 10.0),
            units="mm",
        ),
        "irregularity": Param(float, 0.25, "ice flake: outline radius variation (fraction)", range=(0.0, 0.6)),
        "curl": Param(
            float,
            0.0,
            "ice flake: how far the ends rise above the middle, as a fraction of half the length (a curled shaving)",
            range=(0.0, 1.0),
        ),
        "shape_seed": Param(
            int, 0, "ice flake: which irregular outline (a shape number, not the recipe seed)", range=(0, 2**31 - 1)
        ),
        "path": Param(
            str, None, "file: mesh file in any trimesh format (.stl, .obj, .ply, .off, .glb)", nullable=True, file=True
        ),
        "scale": Param(float, 1.0, "file: factor from the file's units to mm", range=(1e-6, 1e6)),
        "align": Param(bool, True, "file: turn the principal axes onto x ≥ y ≥ z (long axis x)"),
        "subdivisions": Param(int, 2, "icosphere subdivisions of rice/ikura (2 → 320 faces per shell)", range=(0, 5)),
    },
    random=True,
    check=_check,
    check_work=element_fits,
    moved={"variety": Moved("variety", "variety", "rice_variety")},
)
def base_mesh(
    ctx,
    variety=None,
    *,
    shape,
    size,
    bluntness,
    bend,
    diameter,
    diameter_sd,
    lipid_fraction,
    eye_gap,
    irregularity,
    curl,
    shape_seed,
    path,
    scale,
    align,
    subdivisions,
):
    """Low-resolution element model: rice grain preset, ikura egg (membrane + yolk parts), ice flake, chestnut
    piece, or a file.

    Rice: a blunted, slightly bent ellipsoid; the variety (input) multiplies the length (SPEC §1.1), its
    expansion P is applied later by ``expand``. Ikura: parts 0 = outer membrane, 1 = yolk, both
    outward shells, the yolk ``eye_gap`` under the membrane along +z (the eye); with ``diameter_sd`` each variant
    draws its diameter from a normal law clipped at ±2 sd
    (seeded: the same recipe and seed give the same eggs). Files are repaired (merge, drop degenerate faces,
    un-invert, recentre) or refused.
    """
    from . import mesh_files

    if variety is not None and shape != "rice":
        raise ValueError(f"input 'variety' ({variety.name}) is only read by shape 'rice' (shape is '{shape}')")
    if shape == "rice":
        length, width, thickness = size or DEFAULT_SIZE["rice"]
        if variety is not None:
            length *= variety.length_factor
        vertices, faces = grain_shapes.rice_grain(length, width, thickness, bluntness, bend, subdivisions)
        return Mesh(vertices, faces, name="rice" if variety is None else variety.name)
    if shape == "ikura":
        if diameter_sd > 0:
            diameter += diameter_sd * max(-2.0, min(2.0, float(ctx.rng.standard_normal())))
        vertices, faces, parts = grain_shapes.ikura_egg(diameter, lipid_fraction, subdivisions + 1, eye_gap)
        return Mesh(vertices, faces, parts=parts, name="ikura")
    if shape == "ice_flake":
        length, width, thickness = size or DEFAULT_SIZE["ice_flake"]
        vertices, faces = grain_shapes.ice_flake(length, width, thickness, irregularity, shape_seed, curl)
        return Mesh(vertices, faces, name="ice_flake")
    if shape == "chestnut":  # each variant its own cuts, seeded
        length, width, thickness = size or DEFAULT_SIZE["chestnut"]
        vertices, faces = grain_shapes.chestnut_piece(length, width, thickness, ctx.rng, subdivisions)
        return Mesh(vertices, faces, name="chestnut")
    if not path:
        raise ValueError("shape 'file' needs the parameter path (a mesh file)")
    changes: list[str] = []
    vertices, faces = mesh_files.load_element_mesh(path, scale, align, changes)
    if changes:
        from ..mesh_io import repair_line

        ctx.warn(repair_line(path, changes))
    return Mesh(vertices, faces, name=path.rsplit("/", 1)[-1])
