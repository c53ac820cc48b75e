"""Grain skin (issue 26) — the skin score of every rice recipe's grain library, before (G's porosity spheres
centred on the skin, no blur) and after (``sphere_scatter.sink``, ``remesh.blur`` as the recipes set them), and
the porosity sweep's picture: one grain per sink × blur.

    python benchmarks/bench_skin.py [--quick]
    python benchmarks/bench_skin.py --exported [--small]   # the dented grains per variety × water content

The skin score (``nodes/quality/skin.py``) is the concave share of a mesh's edge curvature: 0 for a convex
ellipsoid, ≈ 0.17 for an ellipsoid with 4 % sinusoidal bumps; cooked rice should score ≤ 0.10. The water content
is the recipe's ``cooked`` node's: it sets the optics and the physics, not the grain mesh, so a grain scores the
same at every water content. ``--quick``: the main job and the three varieties only, 4 grains each.
Writes benchmarks/results/bench_skin.md (or under $NODEGRAPH_BENCH_RESULTS) and the committed
docs/images/skin_sweep.png; ``--quick`` (and any run with $NODEGRAPH_BENCH_RESULTS) writes the picture beside
the table instead, never into docs/.
``--exported``: the skin of the grains the recipe exports, after the run and ``deform_contacts``: the full-size
rice bowl per variety × water content (≈ 12 min on 2 cores); there the water content counts, through the physics
(adhesion, stiffness: how the grains pack, so how many dents and how deep). ``--small``: a 28 mm bowl with the
recipe's grains at full resolution (≈ 80 grains, a minute), which hid the dry heap's collapse (at 0 % water it
scored 0.106 where the full bowl scored 0.133: the fewer grains above, the less they nest).
Writes benchmarks/results/bench_skin_exported.md (``--small``: bench_skin_exported_small.md).
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

ROOT = Path(__file__).resolve().parents[1]
RECIPES = ["ikura_don", "rice_bowl", "onigiri", "sushi", "rice_bunny", "rice_chestnut", "water_series"]
VARIETIES = ["japonica", "indica", "aromatic"]
SINKS = (0.0, 0.3, 0.6, 0.9)
BLURS = (0.0, 0.3)


def library_scores(recipe_name: str, overrides: list[str], variants: int | None) -> tuple[list[float], dict]:
    """Skin scores of the recipe's rice library (``rice.library``) under ``overrides``, and its cooked params."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
    from nodes.quality.skin import skin_score

    extra = [f"grain_spheres.variants={variants}"] if variants else []
    recipe = load_recipe(ROOT / "graphs" / f"{recipe_name}.yaml", default_registry(), overrides + extra)
    library = next(k for k in ("rice", "grains") if k in recipe.nodes)
    with tempfile.TemporaryDirectory() as tmp:
        result = run_recipe(recipe, outputs=[f"{library}.library"], cache=Cache(Path(tmp) / "cache"))
        meshes = result.output(f"{library}.library").meshes
    cooked = next((n.params for n in recipe.nodes.values() if n.spec.type_name == "cooked_rice"), {})
    variety = next((n.params["variety"] for n in recipe.nodes.values() if n.spec.type_name == "rice_variety"), "?")
    return [skin_score(m.vertices, m.faces) for m in meshes], {"variety": variety, **cooked}


def sweep_grains(variety: str = "japonica", seed: int = 2):
    """One grain per (blur, sink): the recipes' chain (40 spheres of 0.15–0.35 mm, 70 % at the skin, 40 cells,
    1,800 faces), the same spheres drawn for every cell of the sweep."""
    from nodes.elements import base_mesh, distance_field, expand, remesh, rice_variety, sphere_scatter, voxelise
    from nodes.quality.skin import skin_score

    base = base_mesh.call(variety=rice_variety.call(variety=variety))
    grains = []
    for blur in BLURS:
        for sink in SINKS:
            spheres = sphere_scatter.call(
                seed=seed, mesh=base, count=40, radius_range=(0.15, 0.35), surface_share=0.7, sink=sink
            )
            volume = voxelise.call(mesh=base, spheres=spheres, resolution=40)
            field = distance_field.call(volume=volume, mesh=base, spheres=spheres)
            grown = expand.call(seed=seed, field=field, expansion=(1.3, 1.3))
            mesh = remesh.call(field=grown, target_faces=1800, blur=blur)
            grains.append((blur, sink, mesh, skin_score(mesh.vertices, mesh.faces)))
    return grains


def render_sweep(grains, path: Path, width: int = 1280, height: int = 560, spp: int = 32) -> None:
    """The sweep's grains in a row per blur, lit by a soft key and a sky, white diffuse: the skin alone."""
    import imageio.v3 as iio
    import mitsuba as mi

    from nodes.export.mesh_files import linear_to_srgb8, write_ply

    mi.set_variant("scalar_rgb")
    shapes = {}
    with tempfile.TemporaryDirectory() as tmp:
        for k, (blur, sink, mesh, _) in enumerate(grains):
            row, col = BLURS.index(blur), SINKS.index(sink)
            offset = np.array([(col - 1.5) * 8.5, 0.0, (0.5 - row) * 6.5])
            turned = mesh.vertices[:, [0, 2, 1]] * [1.0, 1.0, -1.0]  # the flat side towards the camera (−y)
            normals = mesh.normals[:, [0, 2, 1]] * [1.0, 1.0, -1.0]
            file = Path(tmp) / f"g{k}.ply"
            write_ply(file, turned + offset, mesh.faces[:, [0, 2, 1]], normals, np.ones((len(turned), 3)))
            shapes[f"g{k}"] = {"type": "ply", "filename": str(file), "bsdf": {"type": "diffuse"}}
        scene = mi.load_dict(
            {
                "type": "scene",
                "integrator": {"type": "path", "max_depth": 6},
                "sensor": {
                    "type": "perspective",
                    "fov": 30.0,
                    "to_world": mi.ScalarTransform4f().look_at(origin=[0, -70, 0], target=[0, 0, 0], up=[0, 0, 1]),
                    "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
                    "sampler": {"type": "independent", "sample_count": spp},
                },
                "sky": {"type": "constant", "radiance": {"type": "rgb", "value": 0.12}},
                "key": {
                    "type": "sphere",
                    "center": [-60.0, -80.0, 90.0],
                    "radius": 20.0,
                    "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 30.0}},
                },
                **shapes,
            }
        )
        image = np.asarray(mi.render(scene, seed=0), np.float32)[..., :3]
    path.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(path, linear_to_srgb8(image))


EXPORTED_BOWL = ["bowl.size=14.0", "bowl.depth=12.0", "bowl.mound=5.0"]  # the draft's bowl, the full grains
WATER = (0.0, 15.0, 24.0)


def exported_scores(variety: str, water: float, cache_dir: Path, small: bool = False) -> dict:
    """Skin of the rice bowl's library, its grains after the run and after ``deform_contacts`` (all of them)."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
    from nodes.quality.skin import skin_score

    overrides = (EXPORTED_BOWL if small else []) + [f"variety.variety={variety}", f"cooked.water_content={water:g}"]
    recipe = load_recipe(ROOT / "graphs" / "rice_bowl.yaml", default_registry(), overrides)
    outputs = ["rice.library", "rice_sim.aggregate", "contact.aggregate", "measure.table"]
    result = run_recipe(recipe, outputs=outputs, cache=Cache(cache_dir))

    def skins(aggregate):
        meshes = (aggregate.element_mesh(i) for i in range(len(aggregate.placement)))
        return [skin_score(m.vertices, m.faces) for m in meshes]

    library = [skin_score(m.vertices, m.faces) for m in result.output("rice.library").meshes]
    contacts = float(result.output("measure.table").columns["contacts_per_element"][0])
    return {
        "grains": len(result.output("contact.aggregate").placement),
        "library": float(np.mean(library)),
        "run": float(np.mean(skins(result.output("rice_sim.aggregate")))),
        "dented": skins(result.output("contact.aggregate")),
        "contacts": contacts,
    }


def exported_table(small: bool = False) -> list[str]:
    lines = [
        "| variety | water content (%) | grains | contacts per grain | skin: library | after the run "
        "| after deform_contacts (mean / p90) |",
        "|---|---|---|---|---|---|---|",
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for variety in VARIETIES:
            for water in WATER:
                r = exported_scores(variety, water, Path(tmp) / "cache", small)
                lines.append(
                    f"| {variety} | {water:g} | {r['grains']} | {r['contacts']:.2f} | {r['library']:.3f} "
                    f"| {r['run']:.3f} | {np.mean(r['dented']):.3f} / {np.percentile(r['dented'], 90):.3f} |"
                )
                print(lines[-1], flush=True)
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the main job and the varieties, 4 grains each")
    parser.add_argument("--exported", action="store_true", help="the dented grains per variety × water content")
    parser.add_argument("--small", action="store_true", help="with --exported: a 28 mm bowl instead of the recipe's")
    args = parser.parse_args(argv)
    out = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS", ROOT / "benchmarks" / "results"))
    if args.exported:
        lines = exported_table(args.small)
        out.mkdir(parents=True, exist_ok=True)
        name = "bench_skin_exported_small.md" if args.small else "bench_skin_exported.md"
        (out / name).write_text("\n".join(lines) + "\n")
        print(f"wrote {out / name}")
        return
    variants = 4 if args.quick else None
    before = ["grain_spheres.sink=0.0", "grain_mesh.blur=0.0"]
    lines = [
        "| recipe | variety | water content (%) | grains | skin before (mean / max) | skin after (mean / max) |",
        "|---|---|---|---|---|---|",
    ]
    rows = [("ikura_don", [])] + [("ikura_don", [f"variety.variety={v}"]) for v in VARIETIES[1:]]
    if not args.quick:
        rows += [(name, []) for name in RECIPES[1:]]
    for name, extra in rows:
        old, info = library_scores(name, before + extra, variants)
        new, _ = library_scores(name, extra, variants)
        water = info.get("water_content", "—")
        lines.append(
            f"| {name} | {info['variety']} | {water} | {len(new)} | {np.mean(old):.3f} / {np.max(old):.3f} "
            f"| {np.mean(new):.3f} / {np.max(new):.3f} |"
        )
        print(lines[-1], flush=True)
    grains = sweep_grains()
    lines += ["", "Porosity sweep (japonica, one seed, P = 1.3; rows: remesh.blur, columns: sphere_scatter.sink):", ""]
    lines += ["| blur (mm) \\ sink | " + " | ".join(f"{s:g}" for s in SINKS) + " |", "|---" * (len(SINKS) + 1) + "|"]
    for blur in BLURS:
        cells = [f"{score:.3f}" for b, _, _, score in grains if b == blur]
        lines.append(f"| {blur:g} | " + " | ".join(cells) + " |")
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench_skin.md").write_text("\n".join(lines) + "\n")
    picture = out / "skin_sweep.png"  # a smoke run's picture is not the committed one
    if not args.quick and "NODEGRAPH_BENCH_RESULTS" not in os.environ:
        picture = ROOT / "docs" / "images" / "skin_sweep.png"
    render_sweep(grains, picture)
    print("\n".join(lines[-(len(BLURS) + 5) :]))
    print(f"wrote {out / 'bench_skin.md'} and {picture}")


if __name__ == "__main__":
    main()
