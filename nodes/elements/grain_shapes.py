"""Low-resolution base models of elements — SPEC §1.1 (G §3.1.1, G eq. 10).

Every shape is built watertight and outward-oriented, in millimetres, centred at its volume
centroid with the long axis along x (the canonical element frame the placement and simulation use).
Only numpy here; the meshes come from an icosphere built by subdivision, so no library is needed.
"""

from __future__ import annotations

import numpy as np

from ..values import RiceVariety

# base_mesh's size when none is given. Rice: a raw Japanese short grain (Koshihikari, brown): length 5.18 ± 0.17 mm,
# width 2.99 ± 0.11 mm (MAFF variety table, 18 prefectures), thickness 1.99 mm (mean of 20 Ibaraki fields); sources
# and what the exported files measure: docs/sizes.md. Chestnut: a peeled Japanese chestnut kernel (Castanea crenata
# nuts are 1–2 in, 25–50 mm, across: acf.org/resources/identification/japanese-chestnuts), 26 mm, at the small end,
# whose quarters are 15–20 mm long (17 mm on average; 5–95 % of 300 draws, icosphere subdivisions 4).
DEFAULT_SIZE = {"rice": (5.2, 3.0, 2.0), "ice_flake": (4.0, 3.0, 0.4), "chestnut": (26.0, 23.0, 17.0)}

#: SPEC §1.1 table (G §3.1.1): indica 1.8 / 1.2, japonica 1.0 / 1.5, aromatic 0.7 / 1.5 (length factor / P).
RICE_VARIETIES = {
    "indica": RiceVariety("indica", 1.8, 1.2),
    "japonica": RiceVariety("japonica", 1.0, 1.5),
    "aromatic": RiceVariety("aromatic", 0.7, 1.5),
}


def icosphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit icosphere (vertices on the unit sphere, outward CCW faces), by midpoint subdivision."""
    t = (1.0 + 5.0**0.5) / 2.0
    vertices = np.array(
        [
            [-1, t, 0],
            [1, t, 0],
            [-1, -t, 0],
            [1, -t, 0],
            [0, -1, t],
            [0, 1, t],
            [0, -1, -t],
            [0, 1, -t],
            [t, 0, -1],
            [t, 0, 1],
            [-t, 0, -1],
            [-t, 0, 1],
        ],
        float,
    )
    faces = np.array(
        [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ],
        np.int64,
    )
    vertices /= np.linalg.norm(vertices, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        mids = vertices[unique].mean(axis=1)
        mids /= np.linalg.norm(mids, axis=1, keepdims=True)
        m = len(vertices) + inverse.reshape(3, -1).T  # midpoints of edges 01, 12, 20 of each face
        vertices = np.concatenate([vertices, mids])
        a, b, c = faces.T
        faces = np.concatenate(
            [
                np.stack([a, m[:, 0], m[:, 2]], 1),
                np.stack([b, m[:, 1], m[:, 0]], 1),
                np.stack([c, m[:, 2], m[:, 1]], 1),
                m,
            ]
        )
    return vertices, faces


def volume_centroid(vertices: np.ndarray, faces: np.ndarray) -> tuple[float, np.ndarray]:
    """Signed volume and centroid of a closed mesh (divergence theorem over tetrahedra).

    The tetrahedra meet at the vertex mean, not the origin, so a mesh far away loses no precision.
    """
    reference = vertices.mean(axis=0)
    a, b, c = (vertices[faces[:, i]] - reference for i in range(3))
    six_v = np.einsum("ij,ij->i", a, np.cross(b, c))
    volume = six_v.sum() / 6.0
    if volume == 0.0:
        return 0.0, reference
    centroid = ((a + b + c) * six_v[:, None]).sum(axis=0) / (24.0 * volume)
    return volume, reference + centroid


def rice_grain(
    length: float, width: float, thickness: float, bluntness: float = 0.8, bend: float = 0.05, subdivisions: int = 2
) -> tuple[np.ndarray, np.ndarray]:
    """A rice grain: a blunted ellipsoid (long axis x) with a slight bend in y, centred.

    ``bluntness`` < 1 squares the ends (each unit-sphere coordinate u ↦ sign(u)|u|^bluntness, a
    monotone map, so the surface stays embedded and outward); ``bend`` shifts y by
    ``bend·width·(2x/length)²`` — the dorsal curve of a real kernel.
    """
    vertices, faces = icosphere(subdivisions)
    vertices = np.sign(vertices) * np.abs(vertices) ** bluntness
    vertices *= np.array([length, width, thickness]) / 2.0
    vertices[:, 1] += bend * width * (2.0 * vertices[:, 0] / length) ** 2
    _, centroid = volume_centroid(vertices, faces)
    return vertices - centroid, faces


def ikura_egg(diameter: float, lipid_fraction: float, subdivisions: int = 3, eye_gap: float = 0.0):
    """Ikura egg: membrane sphere r_i around a yolk sphere r_o = r_i·∛L — SPEC §1 (G eq. 10, Reading).

    The yolk is the egg's oil, which floats up against the membrane: with ``eye_gap`` > 0 its centre moves along
    +z until its surface is ``eye_gap`` under the membrane (the eye a photograph shows; 0: concentric, as G).
    Returns vertices, faces and per-face parts (0 = outer membrane, 1 = yolk). Both shells face
    outward, each the boundary of its own solid; the white is the space between them.
    """
    unit, unit_faces = icosphere(subdivisions)
    r_i = diameter / 2.0
    r_o = r_i * lipid_fraction ** (1.0 / 3.0)
    lift = max(0.0, r_i - r_o - eye_gap) if eye_gap > 0 else 0.0
    vertices = np.concatenate([unit * r_i, unit * r_o + np.array([0.0, 0.0, lift])])
    faces = np.concatenate([unit_faces, unit_faces + len(unit)])
    parts = np.repeat(np.array([0, 1], np.int32), len(unit_faces))
    return vertices, faces, parts


def ice_flake(
    length: float,
    width: float,
    thickness: float,
    irregularity: float = 0.25,
    shape_seed: int = 0,
    curl: float = 0.0,
    segments: int = 24,
) -> tuple[np.ndarray, np.ndarray]:
    """A shaved-ice flake (kakigori, SPEC §1): a thin plate with an irregular star-shaped outline, curled.

    The outline radius varies by up to ``irregularity`` (a fraction) through a few random low
    harmonics fixed by ``shape_seed`` (a shape parameter, like a preset number: same seed, same flake).
    A shaving curls as the blade lifts it: the plate bends along its length, its ends rising ``curl`` × half the
    length above its middle (a parabola, the same shift top and bottom, so it stays closed and outward).
    The plate is closed by a fan on top and bottom around the centre, with quads on the rim.
    """
    rng = np.random.default_rng(shape_seed)
    angles = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    harmonics = np.arange(2, 6)
    amplitude = rng.uniform(-1.0, 1.0, len(harmonics)) / harmonics
    phase = rng.uniform(0.0, 2.0 * np.pi, len(harmonics))
    wobble = (amplitude[:, None] * np.cos(harmonics[:, None] * angles + phase[:, None])).sum(axis=0)
    wobble *= irregularity / max(np.abs(wobble).max(), 1e-12)
    rim = np.stack([np.cos(angles) * length / 2, np.sin(angles) * width / 2], axis=1) * (1.0 + wobble)[:, None]
    half = thickness / 2.0
    top = np.column_stack([rim, np.full(segments, half)])
    bottom = np.column_stack([rim, np.full(segments, -half)])
    vertices = np.concatenate([top, bottom, [[0.0, 0.0, half], [0.0, 0.0, -half]]])
    vertices[:, 2] += curl * (length / 2.0) * (2.0 * vertices[:, 0] / length) ** 2
    s = np.arange(segments)
    n = (s + 1) % segments
    ct, cb = 2 * segments, 2 * segments + 1
    faces = np.concatenate(
        [
            np.column_stack([np.full(segments, ct), s, n]),  # top, normal +z
            np.column_stack([np.full(segments, cb), n + segments, s + segments]),  # bottom, normal −z
            np.column_stack([s, s + segments, n + segments]),  # rim
            np.column_stack([s, n + segments, n]),
        ]
    )
    _, centroid = volume_centroid(vertices, faces)
    return vertices - centroid, faces


# A piece of peeled chestnut (kuri gohan): the kernel cut in quarters by two cuts through near its middle, each
# tilted up to CUT_TILT degrees and off the middle by up to CUT_OFFSET of the kernel's half-size,
# its face that lay against a neighbour in the bur flat (FLAT_FACE of its half-thickness from the middle), and its
# outer face pared by the knife that took its pellicle (shibukawa) off: KNIFE_FACETS flat facets, each shaving a cap
# KNIFE_DEPTH deep (shares of the half-size). Chosen to match a cook's cut, not measured.
CUT_TILT, CUT_OFFSET, FLAT_FACE = 20.0, 0.12, 0.8
# a piece's longest side (its principal frame's x) as a share of the kernel's longest side, at most: 0.81 the
# longest of 300 draws (seeds 0–299) of the 26 × 23 × 17 mm kernel
CHESTNUT_PIECE_SHARE = 0.85
KNIFE_FACETS, KNIFE_DEPTH = 2, (0.04, 0.10)


def chestnut_piece(
    length: float, width: float, thickness: float, rng: np.random.Generator, subdivisions: int = 4
) -> tuple[np.ndarray, np.ndarray]:
    """A peeled chestnut piece: a kernel (an ellipsoid ``length × width × thickness``) cut by knife planes: two
    cuts through near its middle (a quarter), its flat face, and a few shallow facets pared off its rounded back.
    The piece is convex, so every ray from a point inside leaves it once: an icosphere's vertices moved along
    their rays to where each leaves it (the nearest of the ellipsoid and the planes) make a closed outward mesh
    with flat faces where the knife cut and rounded ones where the kernel's skin was. By hand rather than trimesh's
    ``slice_plane(cap=True)``: the caps it adds are fans of slivers, where this keeps the icosphere's even triangles
    and its vertex count for every variant. Centred, long axis x; ``rng`` draws the cuts (a seeded variant)."""
    from .mesh_files import principal_frame

    axes = np.array([length, width, thickness]) / 2.0
    planes = [(np.array([0.0, 0.0, 1.0]), -FLAT_FACE * axes[2])]  # keep n·x ≥ o
    for axis in (0, 1):
        normal = _tilted(np.eye(3)[axis] * rng.choice([-1.0, 1.0]), CUT_TILT, rng)
        planes.append((normal, -CUT_OFFSET * axes[axis] * rng.uniform(-1.0, 1.0)))
    inside = _points_inside(axes, planes, rng)
    for _ in range(KNIFE_FACETS):  # a facet across the outer face: a cap cut off where the knife went
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        if inside.mean(axis=0) @ normal > 0:  # kept side towards the kernel's middle: the knife pares the back
            normal = -normal
        reach = np.min(inside @ normal)  # the piece's extent along −normal, from its points
        planes.append((normal, reach + rng.uniform(*KNIFE_DEPTH) * float(np.abs(normal) @ axes)))
    centre = _points_inside(axes, planes, rng).mean(axis=0)
    directions, faces = icosphere(subdivisions)
    reach = _ray_to_ellipsoid(centre, directions, axes)
    for normal, offset in planes:
        toward = directions @ normal
        room = centre @ normal - offset
        out = toward < -1e-12
        reach[out] = np.minimum(reach[out], room / -toward[out])
    vertices = centre + reach[:, None] * directions
    _, centroid = volume_centroid(vertices, faces)
    vertices = vertices - centroid
    return vertices @ principal_frame(vertices), faces


def _tilted(direction: np.ndarray, degrees: float, rng: np.random.Generator) -> np.ndarray:
    """``direction`` (normalised) turned by up to ``degrees`` about a random axis."""
    direction = direction / np.linalg.norm(direction)
    turn = np.cross(direction, rng.normal(size=3))
    turn /= np.linalg.norm(turn)
    angle = np.radians(degrees) * rng.uniform(-1.0, 1.0)
    return direction * np.cos(angle) + turn * np.sin(angle)


def _points_inside(axes: np.ndarray, planes, rng: np.random.Generator, count: int = 4000) -> np.ndarray:
    """Points drawn uniformly in the ellipsoid that every plane keeps (its mean lies inside: the body is convex)."""
    points = rng.uniform(-1.0, 1.0, (count, 3))
    points = points[(points**2).sum(axis=1) <= 1.0] * axes
    for normal, offset in planes:
        points = points[points @ normal >= offset]
    return points


def _ray_to_ellipsoid(centre: np.ndarray, directions: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Distance along each unit direction from ``centre`` (inside) to the ellipsoid of semi-axes ``axes``."""
    c, d = centre / axes, directions / axes
    a, b, k = (d * d).sum(axis=1), 2.0 * d @ c, c @ c - 1.0
    return (-b + np.sqrt(b * b - 4.0 * a * k)) / (2.0 * a)
