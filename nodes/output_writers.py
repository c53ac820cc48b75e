"""How the built-in value types are written as a recipe's outputs: libraries and aggregates as .glb
(one glTF node per element), registered on the engine's ``write_output`` dispatch; writes are atomic.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nodegraph.cache import atomic_write
from nodegraph.output_files import write_output
from nodegraph.values import Mesh

from .values import Aggregate, ElementLibrary


def _glb(meshes: list[Mesh], names: list[str]) -> bytes:
    import trimesh

    scene = trimesh.Scene()
    for mesh, name in zip(meshes, names):
        colors = None if mesh.colors is None else np.asarray(mesh.colors)
        scene.add_geometry(
            trimesh.Trimesh(mesh.vertices, mesh.faces, vertex_colors=colors, process=False),
            node_name=name,
            geom_name=name,
        )
    return trimesh.exchange.gltf.export_glb(scene)


@write_output.register
def _(value: ElementLibrary, directory: Path, stem: str) -> list[Path]:
    """All elements of the library in one .glb, laid out as they are (each centred at the origin)."""
    path = directory / f"{stem}.glb"
    atomic_write(path, _glb(list(value.meshes), [f"{value.kind}_{i:03d}" for i in range(len(value))]))
    return [path]


@write_output.register
def _(value: Aggregate, directory: Path, stem: str) -> list[Path]:
    """The placed elements in world space, one glTF node each."""
    path = directory / f"{stem}.glb"
    meshes = [value.element_mesh(i) for i in range(len(value.placement))]
    atomic_write(path, _glb(meshes, [f"element_{i:05d}" for i in range(len(meshes))]))
    return [path]
