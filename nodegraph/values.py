"""The generic value types the engine itself reads, writes and logs: meshes, images, file sets, tables.

Each is a frozen dataclass of numpy arrays (struct of arrays) plus plain fields, so the engine can
store it without pickle (``codec``), hash it, freeze it and log it to Rerun (``rerun_log``). A node
package defines its own vocabulary the same way (frozen dataclasses of arrays) and registers how its
types are logged (``rerun_log.log_value.register``) and written (``output_files.write_output.register``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def as_array(array, dtype, shape_tail: tuple[int, ...], name: str) -> np.ndarray:
    """``array`` as ``dtype`` with shape (n, *shape_tail), or a ValueError naming the field."""
    out = np.asarray(array, dtype=dtype)
    if out.ndim != 1 + len(shape_tail) or out.shape[1:] != shape_tail:
        raise ValueError(f"{name}: expected shape (n, {', '.join(map(str, shape_tail))}), got {out.shape}")
    return out


def optional_array(array, dtype, shape_tail, name, rows: int) -> np.ndarray | None:
    """As ``as_array`` with exactly ``rows`` rows; None stays None (an absent optional field)."""
    if array is None:
        return None
    out = as_array(array, dtype, shape_tail, name)
    if len(out) != rows:
        raise ValueError(f"{name}: {len(out)} rows, expected {rows}")
    return out


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh; ``parts`` optionally labels each face with an integer part id."""

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None = None
    colors: np.ndarray | None = None
    parts: np.ndarray | None = None
    name: str = ""

    def __post_init__(self):
        object.__setattr__(self, "vertices", as_array(self.vertices, np.float64, (3,), "vertices"))
        object.__setattr__(self, "faces", as_array(self.faces, np.int64, (3,), "faces"))
        n = len(self.vertices)
        object.__setattr__(self, "normals", optional_array(self.normals, np.float64, (3,), "normals", n))
        if self.colors is not None:
            colors = np.asarray(self.colors)
            if colors.ndim != 2 or colors.shape[1] not in (3, 4) or len(colors) != n:
                raise ValueError(f"colors: expected shape ({n}, 3|4), got {colors.shape}")
            object.__setattr__(self, "colors", colors)
        if self.parts is not None:
            parts = np.asarray(self.parts, dtype=np.int32)
            if parts.shape != (len(self.faces),):
                raise ValueError(f"parts: expected shape ({len(self.faces)},), got {parts.shape}")
            object.__setattr__(self, "parts", parts)

    @classmethod
    def from_trimesh(cls, mesh, name: str = "", parts=None) -> Mesh:
        return cls(
            np.asarray(mesh.vertices),
            np.asarray(mesh.faces),
            normals=np.asarray(mesh.vertex_normals),
            parts=parts,
            name=name,
        )

    def to_trimesh(self):
        import trimesh

        return trimesh.Trimesh(self.vertices.copy(), self.faces.copy(), process=False)

    @property
    def bounds(self) -> np.ndarray:
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])


@dataclass(frozen=True, eq=False)
class Image:
    """An RGB(A) image, uint8, shape (height, width, 3|4)."""

    pixels: np.ndarray

    def __post_init__(self):
        pixels = np.asarray(self.pixels)
        if pixels.dtype != np.uint8 or pixels.ndim != 3 or pixels.shape[2] not in (3, 4):
            raise ValueError(f"pixels: expected uint8 (h, w, 3|4), got {pixels.dtype} {pixels.shape}")
        object.__setattr__(self, "pixels", pixels)


@dataclass(frozen=True, eq=False)
class FileSet:
    """Named file contents produced by a node (e.g. .glb, .usda); the engine writes them out atomically."""

    files: dict[str, bytes]


@dataclass(frozen=True, eq=False)
class Table:
    """Named columns of equal length: measurements, per-step diagnostics, benchmark rows."""

    columns: dict[str, np.ndarray]
    index: str = ""

    def __post_init__(self):
        lengths = {len(np.asarray(v)) for v in self.columns.values()}
        if len(lengths) > 1:
            raise ValueError(f"columns have different lengths: {sorted(lengths)}")
