"""How far each element of an exported scene stands out of the shape it fills (issue 26), read from the .glb only.

Per element (a glTF mesh; its kind is the name before '/'): reach = the largest signed distance of its vertices
outside the shape (mm, fast winding number sign), size = its extent along the shape's outward normal at the point
nearest its centre, share = reach / size (``overlap_refine.protrusion`` bounds it). Prints per kind max / p95 / p50
reach, share max / p95, the count over 25 % and 50 % of its size, wholly outside, and the lowest point.

    nodegraph run graphs/rice_chestnut.yaml --set export.instancing=false --out-dir exp/out
    python benchmarks/protrusion_report.py exp/out/rice_chestnut.glb --kind onigiri --size 76
"""

from __future__ import annotations

import argparse
from collections import defaultdict

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported


def element_vertices(path: str) -> dict[str, list[np.ndarray]]:
    """Each glTF mesh's vertices in the scene's own Z-up millimetres (the root node's Y-up metres undone)."""
    import trimesh

    scene = trimesh.load(path)
    root = np.linalg.inv(scene.graph.get("aggregate")[0])
    kinds = defaultdict(list)
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        vertices = trimesh.transform_points(np.asarray(scene.geometry[name].vertices), root @ transform)
        kinds[name.split("/")[0]].append(vertices)
    return kinds


def reach_and_share(elements: list[np.ndarray], vertices: np.ndarray, faces: np.ndarray):
    """(reach mm, share of size) per element against the closed shape (vertices, faces)."""
    import igl

    centres = np.array([e.mean(axis=0) for e in elements])
    normals = igl.signed_distance(centres, vertices, faces, sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[3]
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    winding = igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER
    distance = igl.signed_distance(np.vstack(elements), vertices, faces, sign_type=winding)[0]
    start = np.cumsum([0] + [len(e) for e in elements])
    reach = np.array([distance[start[i] : start[i + 1]].max() for i in range(len(elements))])
    heights = [e @ n for e, n in zip(elements, normals)]
    size = np.array([h.max() - h.min() for h in heights])
    return reach, reach / size


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("glb")
    parser.add_argument("--kind", default="onigiri", help="the shape node's kind")
    parser.add_argument("--size", type=float, default=76.0, help="the shape node's size (mm)")
    args = parser.parse_args(argv)
    from nodes.shapes import shape

    solid = shape.call(kind=args.kind, size=args.size)["mesh"]
    vertices, faces = np.asarray(solid.vertices, float), np.asarray(solid.faces, np.int64)
    kinds = element_vertices(args.glb)
    for kind, elements in kinds.items():
        reach, share = reach_and_share(elements, vertices, faces)
        print(
            f"{kind}: {len(reach)} elements; reach max {reach.max():.2f} mm, p95 {np.percentile(reach, 95):.2f}, "
            f"p50 {np.percentile(reach, 50):.2f}; share max {share.max():.2f}, p95 {np.percentile(share, 95):.2f}; "
            f"over 25 %: {(share > 0.25).sum()}, over 50 %: {(share > 0.5).sum()}, wholly outside: "
            f"{(share > 1).sum()}, reaching out at all: {(reach > 0).sum()}; lowest z "
            f"{min(e[:, 2].min() for e in elements):.2f}"
        )
    print(f"shape lowest z {vertices[:, 2].min():.2f}")


if __name__ == "__main__":
    main()
