"""Random porosity spheres on the surface and inside a base mesh — SPEC §1.2 (G §3.1.1).

Numpy with a caller-supplied generator, so the same seed gives bit-identical spheres; the inside test
of the interior candidates is the one the voxeliser uses (``nodes.mesh_inside``).
"""

from __future__ import annotations

import numpy as np

from ..kernel_arrays import kernel_array

SURFACE, INSIDE = 0, 1  # SphereSet.tags


def surface_points(
    vertices: np.ndarray, faces: np.ndarray, count: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """``count`` points uniformly distributed by area on the mesh surface, with their faces' unit normals."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    cross = np.cross(b - a, c - a)
    area = np.linalg.norm(cross, axis=1)
    face = rng.choice(len(faces), size=count, p=area / area.sum())
    u, v = rng.random((2, count))
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    points = a[face] + u[:, None] * (b[face] - a[face]) + v[:, None] * (c[face] - a[face])
    return points, cross[face] / area[face, None]


def interior_points(vertices: np.ndarray, faces: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` points uniformly distributed inside the closed mesh (rejection in its bounding box)."""
    from ..mesh_inside import inside_points

    vertices, faces = kernel_array(vertices), kernel_array(faces, np.int64)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    found: list[np.ndarray] = []
    have = 0
    for _ in range(64):
        trial = lo + (hi - lo) * rng.random((max(4 * (count - have), 16), 3))
        keep = trial[inside_points(vertices, faces, trial)]
        found.append(keep)
        have += len(keep)
        if have >= count:
            return np.concatenate(found)[:count]
    raise ValueError(
        f"could not place {count} spheres inside the mesh: it fills under 1/256 of its "
        "bounding box (is it closed and outward-oriented?)"
    )


def scatter_spheres(
    vertices: np.ndarray,
    faces: np.ndarray,
    count: int,
    radius_range: tuple[float, float],
    surface_share: float,
    rng: np.random.Generator,
    sink: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres, radii and tags of ``count`` spheres: a ``surface_share`` of them at the surface.

    Radii are uniform in ``radius_range``; the rest of the spheres have centres uniform inside. A surface
    sphere's centre lies ``sink`` of its radius under the skin, along the face normal (0: on the surface,
    G's spheres; 1: tangent from inside), so it swells the skin by (1 − sink)·r instead of a half-ball bump.
    """
    lo, hi = radius_range
    if not 0.0 < lo <= hi:
        raise ValueError(f"radius_range must satisfy 0 < low ≤ high, got {radius_range}")
    n_surface = int(round(count * surface_share))
    n_inside = count - n_surface
    on_skin, normals = surface_points(vertices, faces, n_surface, rng)
    centers = np.concatenate(
        [on_skin, interior_points(vertices, faces, n_inside, rng) if n_inside else np.empty((0, 3))]
    )
    radii = rng.uniform(lo, hi, count)
    if sink:
        centers[:n_surface] -= (sink * radii[:n_surface])[:, None] * normals
    tags = np.repeat(np.array([SURFACE, INSIDE], np.int8), [n_surface, n_inside])
    return centers, radii, tags
