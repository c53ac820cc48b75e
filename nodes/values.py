"""The domain vocabulary of the built-in nodes: sphere sets, volumes, distance fields, element
libraries, placements, aggregates, particles, vessels, rice varieties, cooked materials, materials and
shaded scenes (SPEC §1–4).

Frozen dataclasses of numpy arrays plus plain fields, like the engine's generic values
(``nodegraph.values``: Mesh, Image, FileSet, Table), so the engine stores, hashes and freezes them
without knowing what they mean; ``rerun_loggers`` and ``output_writers`` register how each is
logged and written. Lengths are in the recipe's length unit (millimetres in the shipped recipes).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from nodegraph.values import Mesh, as_array


@dataclass(frozen=True, eq=False)
class ElementLibrary:
    """N distinct elements of one kind (e.g. 16 japonica grains), each a high-resolution mesh.

    ``props`` holds per-element arrays of length N (e.g. ``expansion``, ``circumradius``);
    ``refine_range`` is the kind's own overlap-refine search range factor (S: chestnut 0.1).
    """

    kind: str
    meshes: tuple[Mesh, ...]
    props: dict[str, np.ndarray] = field(default_factory=dict)
    refine_range: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "meshes", tuple(self.meshes))
        for key, values in self.props.items():
            if len(values) != len(self.meshes):
                raise ValueError(f"props[{key!r}]: {len(values)} values for {len(self.meshes)} meshes")

    def __len__(self) -> int:
        return len(self.meshes)


@dataclass(frozen=True, eq=False)
class SphereSet:
    """Spheres (centre, radius); ``tags`` marks e.g. 0 = on the surface, 1 = inside."""

    centers: np.ndarray
    radii: np.ndarray
    tags: np.ndarray | None = None

    def __post_init__(self):
        object.__setattr__(self, "centers", as_array(self.centers, np.float64, (3,), "centers"))
        radii = np.asarray(self.radii, dtype=np.float64)
        if radii.shape != (len(self.centers),):
            raise ValueError(f"radii: expected shape ({len(self.centers)},), got {radii.shape}")
        object.__setattr__(self, "radii", radii)
        if self.tags is not None:
            object.__setattr__(self, "tags", np.asarray(self.tags, dtype=np.int8))

    def __len__(self) -> int:
        return len(self.radii)


@dataclass(frozen=True, eq=False)
class Volume:
    """A regular grid of cell values; cell (i, j, k) has its centre at ``origin + (i, j, k)·voxel_size``."""

    data: np.ndarray
    origin: np.ndarray
    voxel_size: float

    def __post_init__(self):
        if np.ndim(self.data) != 3:
            raise ValueError(f"data: expected a 3-D grid, got shape {np.shape(self.data)}")
        object.__setattr__(self, "origin", np.asarray(self.origin, dtype=np.float64).reshape(3))
        if not self.voxel_size > 0:
            raise ValueError(f"voxel_size must be > 0, got {self.voxel_size}")

    def cell_centers(self, mask: np.ndarray | None = None) -> np.ndarray:
        idx = np.argwhere(self.data if mask is None else mask)
        return self.origin + idx * self.voxel_size


@dataclass(frozen=True, eq=False)
class DistanceField(Volume):
    """A distance field on a grid (SPEC §1.4, G eq. 5): positive inside, in length units.

    ``metric`` is ``euclidean`` or ``manhattan``; ``signed`` tells whether outside cells carry
    negative distances or zero.
    """

    metric: str = "euclidean"
    signed: bool = True


# the per-element columns of a Placement (every field but ``kind_names``)
PER_ELEMENT = ("positions", "normals", "rotations", "kinds", "variants", "p_num", "offsets", "overlap")


@dataclass(frozen=True, eq=False)
class Placement:
    """Element instances: position, rotation (3×3), kind, surface normal, and P_num (SPEC §2.2–2.4).

    ``kinds[i]`` indexes ``kind_names``; ``variants[i]`` picks the mesh within that kind's library;
    ``offsets`` is the refine displacement t along the normal; ``overlap`` the residual depth; ``spacing`` the
    Poisson radius r the points were placed at (0: not placed by ``poisson_place``), which ``overlap_refine``'s gan
    range follows when it is given no r.
    """

    positions: np.ndarray
    normals: np.ndarray
    rotations: np.ndarray | None = None
    kinds: np.ndarray | None = None
    variants: np.ndarray | None = None
    p_num: np.ndarray | None = None
    offsets: np.ndarray | None = None
    overlap: np.ndarray | None = None
    kind_names: tuple[str, ...] = ()
    spacing: float = 0.0

    def __post_init__(self):
        positions = as_array(self.positions, np.float64, (3,), "positions")
        n = len(positions)
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "normals", as_array(self.normals, np.float64, (3,), "normals"))
        if len(self.normals) != n:
            raise ValueError(f"normals: {len(self.normals)} rows, expected {n}")
        rotations = np.tile(np.eye(3), (n, 1, 1)) if self.rotations is None else np.asarray(self.rotations, np.float64)
        if rotations.shape != (n, 3, 3):
            raise ValueError(f"rotations: expected shape ({n}, 3, 3), got {rotations.shape}")
        object.__setattr__(self, "rotations", rotations)
        defaults = {
            "kinds": np.zeros(n, np.int32),
            "variants": np.zeros(n, np.int32),
            "p_num": np.arange(n, dtype=np.int64),
            "offsets": np.zeros(n),
            "overlap": np.zeros(n),
        }
        for name, default in defaults.items():
            value = getattr(self, name)
            value = default if value is None else np.asarray(value, dtype=default.dtype)
            if value.shape != (n,):
                raise ValueError(f"{name}: expected shape ({n},), got {value.shape}")
            object.__setattr__(self, name, value)
        object.__setattr__(self, "kind_names", tuple(self.kind_names))

    def __len__(self) -> int:
        return len(self.positions)

    def subset(self, keep: np.ndarray) -> Placement:
        """The placement restricted to a boolean mask or index array."""
        return dataclasses.replace(self, **{name: getattr(self, name)[keep] for name in PER_ELEMENT})


@dataclass(frozen=True, eq=False)
class Aggregate:
    """Placed elements with their meshes: a placement plus one library per kind (in kind order)."""

    placement: Placement
    libraries: tuple[ElementLibrary, ...]
    deformations: np.ndarray | None = None  # (n, 3, 3) per-element linear deformation, identity if None
    # (n, 3, 6) per-element quadratic deformation (SPEC §5 quadratic shape matching), none if None:
    # coefficients of the local vertex's monomials [x², y², z², xy, yz, zx] (about the mesh origin,
    # local frame) giving a local-frame displacement, which the rotation turns into world space
    bends: np.ndarray | None = None

    @staticmethod
    def monomials(local: np.ndarray) -> np.ndarray:
        """(k, 6) quadratic monomials [x², y², z², xy, yz, zx] of local points (k, 3) — SPEC §5's q̃ order."""
        x, y, z = local[:, 0], local[:, 1], local[:, 2]
        return np.stack([x * x, y * y, z * z, x * y, y * z, z * x], axis=1)

    def element_points(self, i: int, local: np.ndarray) -> np.ndarray:
        """Points (k, 3) of element i's local frame in world space: D·R·v + R·B·m(v) + t."""
        p = self.placement
        transform = p.rotations[i] if self.deformations is None else self.deformations[i] @ p.rotations[i]
        world = local @ transform.T + p.positions[i]
        if self.bends is not None:
            world += (self.monomials(local) @ self.bends[i].T) @ p.rotations[i].T
        return world

    def element_mesh(self, i: int) -> Mesh:
        """The i-th element's mesh in world space (rotation, deformation, bend, position applied).

        Normals are rotated by R; a bent element's normals go through the map's Jacobian instead
        (cofactor matrix, so they stay normal to the bent surface)."""
        p = self.placement
        base = self.libraries[p.kinds[i]].meshes[p.variants[i] % len(self.libraries[p.kinds[i]])]
        vertices = self.element_points(i, base.vertices)
        if base.normals is None:
            normals = None
        elif self.bends is None:
            normals = base.normals @ p.rotations[i].T
        else:
            normals = self._bent_normals(i, base.vertices, base.normals)
        return Mesh(vertices, base.faces, normals=normals, parts=base.parts, name=f"{base.name}#{i}")

    def without_normals(self) -> Aggregate:
        """The aggregate with normal-free library meshes: its ``element_mesh`` gives the same vertices, faces and
        parts without the normal work (rotating them, bending them, re-normalising a dented element's) — for
        readers of the shapes alone (``measure``; ``shade``, which computes its own normals)."""
        libraries = tuple(
            dataclasses.replace(library, meshes=tuple(dataclasses.replace(m, normals=None) for m in library.meshes))
            for library in self.libraries
        )
        return dataclasses.replace(self, libraries=libraries)

    def _bent_normals(self, i: int, local: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """cof(J)·n, normalised, with J(v) = D·R + R·B·∂m/∂v the Jacobian of ``element_points``."""
        rotation = self.placement.rotations[i]
        linear = rotation if self.deformations is None else self.deformations[i] @ rotation
        x, y, z = local[:, 0], local[:, 1], local[:, 2]
        zero = np.zeros_like(x)
        dm = np.stack(
            [
                np.stack(row, axis=-1)
                for row in (
                    (2 * x, zero, zero),
                    (zero, 2 * y, zero),
                    (zero, zero, 2 * z),
                    (y, x, zero),
                    (zero, z, y),
                    (z, zero, x),
                )
            ],
            axis=1,
        )  # (k, 6, 3)
        jac = linear + np.einsum("ij,jk,vkl->vil", rotation, self.bends[i], dm)
        a, b, c = jac[:, :, 0], jac[:, :, 1], jac[:, :, 2]
        cof = np.stack([np.cross(b, c), np.cross(c, a), np.cross(a, b)], axis=2)  # det(J)·J⁻ᵀ
        out = np.einsum("vij,vj->vi", cof, normals)
        return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-300)

    def combined_mesh(self) -> Mesh | None:
        """Every element in world space as one mesh (None when empty): one draw call in a viewer."""
        meshes = [self.element_mesh(i) for i in range(len(self.placement))]
        if not meshes:
            return None
        offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
        return Mesh(
            np.concatenate([m.vertices for m in meshes]),
            np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]),
            name="aggregate",
        )


@dataclass(frozen=True, eq=False)
class ParticleState:
    """Simulation particles (struct of arrays) at one instant; ``element`` maps particle → element."""

    positions: np.ndarray
    velocities: np.ndarray
    radii: np.ndarray
    inv_mass: np.ndarray
    element: np.ndarray
    time: float = 0.0

    def __len__(self) -> int:
        return len(self.positions)


@dataclass(frozen=True, eq=False)
class Material:
    """A principled BSDF parameter set (G Table 3 colour columns); colours are linear RGB in [0, 1]."""

    name: str
    base_color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    subsurface: float = 0.0
    subsurface_radius: tuple[float, float, float] = (1.0, 1.0, 1.0)
    subsurface_color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    metallic: float = 0.0
    specular: float = 0.5
    roughness: float = 0.5
    anisotropic: float = 0.0
    anisotropic_rotation: float = 0.0
    sheen: float = 0.0  # soft rim of a wet film (Blender principled v1 sheen, KHR_materials_sheen)
    sheen_tint: float = 0.5  # 0: white sheen, 1: sheen in the base colour
    clearcoat: float = 0.0
    clearcoat_roughness: float = 0.03
    ior: float = 1.45
    exterior_ior: float = 1.0  # IOR of what surrounds the surface (the ikura yolk sits in the egg fluid: 1.36)
    transmission: float = 0.0
    transmission_roughness: float = 0.0
    emission: tuple[float, float, float] = (0.0, 0.0, 0.0)
    emission_strength: float = 0.0


@dataclass(frozen=True, eq=False)
class RiceVariety:
    """A rice variety preset of SPEC §1.1 (G §3.1.1): its name (the element kind of its library), the length
    factor on the base grain and the expansion P."""

    name: str
    length_factor: float
    expansion: float


@dataclass(frozen=True, eq=False)
class CookedMaterial:
    """One cooked rice: its variety and water content and the constants both the simulation and the shading
    derive from them — SPEC §3 (moisture: stiffness, friction and adhesion factors, G §2.2) and §4 (CDRF σ₀
    from a log–log line in the water content; the principled material ``optics``)."""

    variety: str
    water_content: float  # % of grain mass
    stiffness_scale: float
    friction_scale: float
    adhesion_scale: float
    sigma0: float  # rad·mm: CDRF blur per unit curvature
    optics: Material


@dataclass(frozen=True, eq=False)
class Vessel:
    """A bowl's cavity as numbers, so regions can be derived from it (``vessel_region``) and elements tested
    against it (``measure``): rim radius, cavity depth below the rim, wall thickness, fill height (share of the
    depth) and mound above the fill plane (mm), the translation, and the mesh resolution level of its shape.
    ``kind`` is 'bowl', or the shape's kind when it is no vessel (then the numbers are 0)."""

    kind: str
    radius: float = 0.0
    depth: float = 0.0
    wall: float = 0.0
    fill: float = 0.0
    mound: float = 0.0
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    resolution: int = 4

    @property
    def fill_z(self) -> float:
        """Height of the fill plane (the rim is at z = offset z)."""
        return self.offset[2] - self.depth + self.fill * self.depth

    def outside(self, points: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """Which points lie outside the vessel: below the rim, outside the cavity's half-ellipsoid (through the
        wall or under the bowl); above it, further from the axis than the rim, or higher over the heap's top (the
        fill plane plus the mound) than the rim's radius: no heap stands steeper than 45° over its whole rim, so
        such an element was thrown. ``margin`` (mm) widens the cavity by that much on every side."""
        p = np.asarray(points, float) - np.asarray(self.offset, float)
        r = np.hypot(p[:, 0], p[:, 1])
        a, b = self.radius + margin, self.depth + margin
        below = (r / a) ** 2 + (np.minimum(p[:, 2], 0.0) / b) ** 2 > 1.0
        top = max(self.fill_z - self.offset[2] + self.mound, 0.0)
        return np.where(p[:, 2] < 0.0, below, (r > a) | (p[:, 2] > top + a))


@dataclass(frozen=True, eq=False)
class ShadedScene:
    """Meshes with per-vertex colours and one material each (``material_of[i]`` indexes ``materials``).

    ``cdrf_sigma[i]`` holds mesh i's per-vertex CDRF kernel width σ = σ₀·|κ| (rad, SPEC §4 eq. 9): what a
    renderer needs to evaluate the curvature-dependent translucency itself instead of the baked colours
    (the preview turns it into diffuse transmission, ``nodes.shading.cdrf.translucency``). Empty: none.

    ``transmittance[i]`` holds, where light through mesh i's element keeps a colour that varies over its skin, that
    colour (linear RGB, in and out) at each vertex: an egg's membrane, paler over its oil droplet (its eye,
    ``scene_shading.eye_transmittance``); an empty array: the material's own. Empty tuple: none anywhere.

    ``key_gain`` scales the preview's key softbox and its glints (``nodes.export.studio.lights``): the shade node's
    first light intensity over its default, so that a brighter key in the recipe is a brighter key in the preview
    and in the Blender side-by-side (which reads the same studio), not only in the baked vertex colours.
    """

    meshes: tuple[Mesh, ...]
    materials: tuple[Material, ...]
    material_of: np.ndarray
    cdrf_sigma: tuple[np.ndarray, ...] = ()
    transmittance: tuple[np.ndarray, ...] = ()
    key_gain: float = 1.0

    def __post_init__(self):
        if not (np.isfinite(self.key_gain) and self.key_gain > 0):
            raise ValueError(f"key_gain = {self.key_gain}: the key light's gain must be > 0")
        object.__setattr__(self, "key_gain", float(self.key_gain))
        object.__setattr__(self, "meshes", tuple(self.meshes))
        object.__setattr__(self, "materials", tuple(self.materials))
        object.__setattr__(self, "material_of", np.asarray(self.material_of, dtype=np.int32))
        sigma = tuple(np.asarray(s, dtype=np.float32) for s in self.cdrf_sigma)
        if sigma and [len(s) for s in sigma] != [len(m.vertices) for m in self.meshes]:
            raise ValueError("cdrf_sigma: one array per mesh, one value per vertex")
        object.__setattr__(self, "cdrf_sigma", sigma)
        tints = tuple(np.asarray(t, dtype=np.float32).reshape(-1, 3) for t in self.transmittance)
        if tints and (
            len(tints) != len(self.meshes)
            or any(len(t) not in (0, len(m.vertices)) for t, m in zip(tints, self.meshes))
        ):
            raise ValueError("transmittance: one array per mesh, empty or one RGB row per vertex")
        object.__setattr__(self, "transmittance", tints)

    def vertex_transmittance(self, k: int) -> np.ndarray | None:
        """Mesh k's per-vertex transmittance (``transmittance``), None where it has none of its own."""
        if not self.transmittance or not len(self.transmittance[k]):
            return None
        return self.transmittance[k]
