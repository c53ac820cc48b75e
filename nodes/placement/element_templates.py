"""Per-element-variant data the refine kernels read: medial spheres and cost points, packed as CSR arrays.

SPEC §2.5–2.6: the implicit function of each variant (its medial spheres, S §3.2.2) and the point set
X whose overlap the cost sums (S uses all vertices; here up to ``cost_points`` spread by farthest-point
sampling, since the cost grows linearly with |X|).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..values import ElementLibrary


@dataclass(frozen=True, eq=False)
class ElementTemplates:
    """Template t = kind_first[kind] + variant; CSR arrays ``*_start`` index ``pts`` and ``centers``/``radii``.

    ``pts`` = up to ``cost_points`` spread vertices (the refine cost's X, as S) then the medial-sphere
    centres, which the overlap depth also probes.
    """

    pts_start: np.ndarray
    cost_end: np.ndarray  # X of the refine cost = pts[pts_start[t]:cost_end[t]] (vertices, as S)
    pts: np.ndarray
    sph_start: np.ndarray
    centers: np.ndarray
    radii: np.ndarray
    bound: np.ndarray  # radius about the origin outside which the implicit function is ≤ 0
    circumradius: np.ndarray  # max vertex distance from the origin (S: b)
    length: np.ndarray  # longest bounding-box extent
    inscribed: np.ndarray  # largest medial sphere radius
    kind_first: np.ndarray
    fit: tuple[dict, ...]

    def index(self, kinds: np.ndarray, variants: np.ndarray) -> np.ndarray:
        counts = np.diff(np.append(self.kind_first, len(self.bound)))
        return self.kind_first[kinds] + variants % counts[kinds]


def farthest_points(points: np.ndarray, count: int) -> np.ndarray:
    """``count`` points spread over the set by farthest-point sampling, starting from the farthest from the origin."""
    if len(points) <= count:
        return points.copy()
    chosen = [int(np.argmax((points**2).sum(axis=1)))]
    distance = np.linalg.norm(points - points[chosen[0]], axis=1)
    for _ in range(count - 1):
        nxt = int(np.argmax(distance))
        chosen.append(nxt)
        distance = np.minimum(distance, np.linalg.norm(points - points[nxt], axis=1))
    return points[chosen]


# ElementLibrary.props keys of carried medial spheres (per mesh; padded rows have radius 0) and their fit.
SPHERES, SPHERE_COUNT = "medial_spheres", "medial_count"
FIT_KEYS = ("spheres", "gap_mean", "gap_max", "volume")


def with_medial_spheres(
    library: ElementLibrary, tolerance: float, max_spheres: int, spacing: float = 0.0
) -> ElementLibrary:
    """The library with each mesh's medial spheres (and their fit) in ``props``, so that refine and cull
    read them instead of recomputing them (~0.3 s per mesh). Stored as an (N, K, 4) array of
    (centre, radius) padded with zero rows plus the count per mesh: props are arrays of length N."""
    from .medial_spheres import union_fit

    if len(library) == 0:
        raise ValueError(f"element library {library.kind!r} holds no meshes")
    found, fits = [], []
    for index, mesh in enumerate(library.meshes):
        c, r = _mesh_spheres(library, index, tolerance, max_spheres, spacing)
        found.append(np.hstack([c, r[:, None]]))
        fits.append(union_fit(mesh.vertices, mesh.faces, c, r))
    packed = np.zeros((len(found), max(len(f) for f in found), 4))
    for index, spheres in enumerate(found):
        packed[index, : len(spheres)] = spheres
    props = dict(library.props)
    props[SPHERES] = packed
    props[SPHERE_COUNT] = np.array([len(f) for f in found], np.int64)
    props.update({f"medial_fit_{key}": np.array([f[key] for f in fits], np.float64) for key in FIT_KEYS})
    return ElementLibrary(library.kind, library.meshes, props, library.refine_range)


def _mesh_spheres(library: ElementLibrary, index: int, tolerance: float, max_spheres: int, spacing: float = 0.0):
    """Medial spheres (centres, radii) of one mesh; an error names the kind and mesh."""
    from .medial_spheres import medial_spheres

    mesh = library.meshes[index]
    try:
        return medial_spheres(mesh.vertices, mesh.faces, tolerance, max_spheres, spacing=spacing)
    except ValueError as exc:
        raise ValueError(f"element {library.kind!r} mesh {index}: {exc}") from None


def _spheres_of(library: ElementLibrary, index: int, tolerance: float, max_spheres: int, measure_fit: bool):
    """(centres, radii, fit) of one mesh: carried in props when there, else computed now."""
    from .medial_spheres import union_fit

    if SPHERES in library.props:
        rows = library.props[SPHERES][index, : int(library.props[SPHERE_COUNT][index])]
        fit = {key: float(library.props[f"medial_fit_{key}"][index]) for key in FIT_KEYS}
        return np.ascontiguousarray(rows[:, :3]), rows[:, 3].copy(), fit
    mesh = library.meshes[index]
    c, r = _mesh_spheres(library, index, tolerance, max_spheres)
    return c, r, union_fit(mesh.vertices, mesh.faces, c, r) if measure_fit else {}


def build_templates(
    libraries: tuple[ElementLibrary, ...],
    tolerance: float,
    max_spheres: int,
    cost_points: int,
    measure_fit: bool = False,
) -> ElementTemplates:
    """Medial spheres (carried in props, else computed) and cost points of every mesh of every library."""
    from .medial_spheres import element_length

    pts, centers, radii, bound, circum, length, inscribed, fit = [], [], [], [], [], [], [], []
    kind_first, cost_counts = [], []
    for library in libraries:
        if len(library) == 0:
            raise ValueError(f"element library {library.kind!r} holds no meshes")
        kind_first.append(len(bound))
        for index, mesh in enumerate(library.meshes):
            c, r, mesh_fit = _spheres_of(library, index, tolerance, max_spheres, measure_fit)
            # Depth probes = spread vertices plus the medial centres: with vertices alone an element lying
            # wholly inside another, or coinciding with it, would register no overlap at all.
            spread = farthest_points(np.asarray(mesh.vertices, np.float64), cost_points)
            cost_counts.append(len(spread))
            pts.append(np.vstack([spread, c]))
            centers.append(c)
            radii.append(r)
            bound.append(float((np.linalg.norm(c, axis=1) + r).max()))
            circum.append(float(np.linalg.norm(mesh.vertices, axis=1).max()))
            length.append(element_length(mesh.vertices))
            inscribed.append(float(r.max()))
            fit.append(mesh_fit)

    def csr(parts):
        start = np.zeros(len(parts) + 1, np.int64)
        np.cumsum([len(p) for p in parts], out=start[1:])
        return start

    pts_start = csr(pts)
    return ElementTemplates(
        pts_start,
        pts_start[:-1] + np.array(cost_counts, np.int64),
        np.ascontiguousarray(np.vstack(pts)),
        csr(radii),
        np.ascontiguousarray(np.vstack(centers)),
        np.concatenate(radii),
        np.array(bound),
        np.array(circum),
        np.array(length),
        np.array(inscribed),
        np.array(kind_first, np.int64),
        tuple(fit),
    )


def template_params():
    """The parameters shared by nodes that evaluate medial-sphere implicit functions."""
    from nodegraph.params import Param

    return {
        "sphere_tolerance": Param(
            float,
            0.02,
            "medial spheres must touch the surface within this share of the element length (only for libraries "
            "not carrying spheres from medial_spheres)",
            range=(0.001, 0.5),
        ),
        "max_spheres": Param(
            int,
            64,
            "most medial spheres per element, cost grows linearly with it (only for libraries not carrying spheres)",
            range=(1, 4096),
        ),
        "cost_points": Param(
            int, 64, "element vertices (farthest-point spread) whose overlap the cost sums (S: all)", range=(4, 100000)
        ),
    }


def with_kind_names(placement, libraries: tuple[ElementLibrary, ...]):
    """The placement naming its kinds: one without (no mix_ratio upstream) takes the single library's kind."""
    if placement.kind_names:
        return placement
    return dataclasses.replace(placement, kind_names=(libraries[0].kind,))


def matching_libraries(placement, libraries) -> tuple[ElementLibrary, ...]:
    """The libraries in the placement's kind order; a placement without kinds takes the single library."""
    libraries = tuple(libraries)
    if not libraries:
        raise ValueError("libraries: at least one element library is needed")
    names = tuple(lib.kind for lib in libraries)
    if not placement.kind_names:
        if len(libraries) != 1:
            raise ValueError(
                f"libraries: the placement has no kinds (no mix_ratio upstream) but {len(libraries)} "
                "libraries were given; mix them with mix_ratio first"
            )
        return libraries
    by_name = dict(zip(names, libraries))
    missing = [k for k in placement.kind_names if k not in by_name]
    if missing:
        raise ValueError(f"libraries: the placement uses kinds {list(placement.kind_names)} but got {list(names)}")
    return tuple(by_name[k] for k in placement.kind_names)
