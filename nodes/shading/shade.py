"""The ``shade`` node: CDRF vertex colours and principled materials per element kind — SPEC §4.

Thin: checks parameters, builds the lights and the CDRF table, calls ``scene_shading.shade_scene``.
"""

from __future__ import annotations

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Moved, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh

from ..values import Aggregate, CookedMaterial, ShadedScene
from .materials import EGG_TINTS

RGB = tuple[float, float, float]
# the key light's intensity by default: the baked vertex colours' key, and the intensity at which the preview's key
# softbox gives its studio irradiance (``nodes.export.studio.KEY_IRRADIANCE``); another value scales both alike
KEY_INTENSITY = 1.2


def _check(params):
    from .materials import parse_overrides

    problems = []
    n = len(params.get("light_directions", ()))
    for name in ("light_colors", "light_intensities"):
        if len(params.get(name, ())) not in (1, n):
            problems.append((name, f"give one value for all lights or one per light ({n} directions)"))
    try:  # a misspelt preset is refused by ``check``, not after the simulation
        parse_overrides(params.get("presets", []))
    except ValueError as error:
        problems.append(("presets", str(error)))
    return problems


@estimated_by(passes("aggregates"))
@node(
    "shade",
    random=True,
    # its scene is large and made in a moment: the ikura draft's 11.7 MB (and a 7.2 MB recording) in 0.35 s, loaded
    # in 0.19 s; the full main job's up to 197 MB in 1.35 s, 48 % of a 2.16 GB cache (benchmarks/measured/cache.jsonl)
    store=False,
    inputs={
        "aggregates": In(Aggregate, "placed or simulated aggregates (rice, ikura, ice)", many=True),
        "material": In(
            CookedMaterial,
            "the cooked rice (a cooked_rice node, the one the xpbd node reads): σ₀ and the rice material; "
            "needed when rice is shaded (a scene without rice uses the cooked_rice defaults' σ₀)",
            optional=True,
        ),
        "scenery": In(
            Mesh,
            "other meshes to show, e.g. the bowl (glazed ceramic; one named 'nori': nori; 'chopsticks': lacquer)",
            optional=True,
            many=True,
        ),
        "filling": In(
            Mesh,
            "the rice under the simulated top layer (a vessel_region's mesh, the rice's static collider), shown in "
            "the cooked rice's material: what gaps between the top grains show (without it, the bowl's dark floor)",
            optional=True,
            many=True,
        ),
    },
    outputs={
        "scene": Out(
            ShadedScene,
            "one mesh per element part with CDRF vertex colours (linear RGB), per-vertex CDRF σ "
            "and its principled material",
        )
    },
    params={
        "light_directions": Param(
            list[RGB], [(-0.45, -0.6, 0.75)], "directions towards each distant light (normalised)", range=(-1.0, 1.0)
        ),
        "light_colors": Param(
            list[RGB],
            [(1.0, 0.97, 0.92)],
            "linear RGB per light (or one for all): the baked vertex colours' (.ply, the recording); the preview's "
            "studio lights are white",
            range=(0.0, 1.0),
        ),
        "light_intensities": Param(
            list[float],
            [KEY_INTENSITY],
            "intensity per light (or one for all; remove a light rather than set it to 0). The first light is the "
            f"key: the preview's key softbox and its glints scale with it ({KEY_INTENSITY}: the studio's own; 2.4: "
            "twice as bright), in the preview and the Blender side-by-side alike; the others light only the baked "
            "vertex colours",
            range=(0.01, 100.0),  # inclusive: at 0 the run refused the light in shade, after the simulations
        ),
        "baked_ambient": Param(
            float,
            0.35,
            "ambient light as a share of the base colour in the baked CDRF vertex colours (the exported .glb, .usdc "
            "and .ply and the recording); the path-traced preview does not use them: its ambient is preview.ambient",
            range=(0.0, 1.0),
        ),
        "presets": Param(
            list[str],
            [],
            "material preset per element kind, 'kind=preset' (rice, ikura, ice, chestnut, salmon, tuna); "
            "kinds named like japonica/ikura/ice/chestnut/salmon/tuna are matched automatically",
        ),
        "syrup_color": Param(RGB, (0.75, 0.02, 0.06), "kakigori syrup colour (linear RGB)", range=(0.0, 1.0)),
        "syrup_depth": Param(
            float,
            15.0,
            "kakigori: how deep the syrup soaks below the mound's top surface (its concentration falls "
            "linearly from 1 at the surface to 0 at this depth); 0 = no syrup",
            range=(0.0, 1e4),
            units="mm",
        ),
        "syrup_spread": Param(
            float,
            10.0,
            "kakigori: how far the syrup runs sideways as it soaks down: the top surface is the highest point "
            "within this radius, so flanks below the summit get less (0: every column's own top is soaked)",
            range=(0.0, 1e4),
            units="mm",
        ),
        "syrup_levels": Param(
            int, 6, "kakigori: syrup grades between plain ice and soaked (one material each)", range=(1, 64)
        ),
        "syrup_runs": Param(
            int,
            0,
            "kakigori: streaks of syrup that run further down the flanks than the rest (random azimuths, drawn from "
            "the recipe's seed); 0: an even band",
            range=(0, 256),
        ),
        "syrup_run_length": Param(
            float,
            0.0,
            "kakigori: how much deeper than syrup_depth the longest run soaks (each run 0.4–1 of it)",
            range=(0.0, 1e4),
            units="mm",
        ),
        "egg_tints": Param(
            int,
            EGG_TINTS,
            "ikura: membrane tints (orange to red-orange, lighter to deeper; shading.materials.ikura_tints) each egg "
            "draws one of, seeded, no two touching eggs alike; 1: every egg alike",
            range=(1, 64),
        ),
        "scenery_color": Param(RGB, (0.05, 0.07, 0.16), "glaze colour of scenery meshes (the bowl)", range=(0.0, 1.0)),
        "scenery_roughness": Param(
            float,
            0.04,
            "roughness of the scenery's glaze: 0.04 a glossy glaze that mirrors the studio's softboxes; ≈ 0.3 a satin "
            "(matte-finished) glaze, whose reflections spread into a soft sheen",
            range=(0.0, 1.0),
        ),
        "table_size": Param(
            tuple[int, int],
            (128, 64),
            "CDRF lookup table samples (θ, σ): accuracy vs time, see benchmarks/bench_shading.py",
            range=(2, 4096),
        ),
    },
    check=_check,
    moved={name: Moved("material", name, "cooked_rice") for name in ("water_content", "sigma0_dry", "sigma0_wet")},
)
def shade(
    ctx,
    aggregates,
    material=None,
    scenery=None,
    filling=None,
    *,
    light_directions,
    light_colors,
    light_intensities,
    baked_ambient,
    presets,
    syrup_color,
    syrup_depth,
    syrup_spread,
    syrup_levels,
    syrup_runs,
    syrup_run_length,
    egg_tints,
    scenery_color,
    scenery_roughness,
    table_size,
):
    """Curvature from libigl, CDRF eq. 7–9 with the cooked material's σ₀(water), lights, and a material per
    element kind/part (rice: the cooked material's)."""
    from ..simulation.moisture import WATER_CONTENT
    from .cdrf import SIGMA0_DRY, SIGMA0_WET, CdrfTable, sigma0_from_water
    from .materials import parse_overrides
    from .scene_shading import ShadeSettings, shade_scene
    from .vertex_shading import check_color, make_lights

    check_color(syrup_color, "syrup_color")
    check_color(scenery_color, "scenery_color")
    settings = ShadeSettings(
        rice=None if material is None else material.optics,
        sigma0=sigma0_from_water(WATER_CONTENT, SIGMA0_DRY, SIGMA0_WET) if material is None else material.sigma0,
        lights=make_lights(light_directions, light_colors, light_intensities),
        ambient=baked_ambient,
        presets=parse_overrides(presets),
        syrup_color=tuple(syrup_color),
        syrup_depth=syrup_depth,
        syrup_spread=syrup_spread,
        syrup_levels=syrup_levels,
        syrup_runs=syrup_runs,
        syrup_run_length=syrup_run_length,
        seed=ctx.seed,
        scenery_color=tuple(scenery_color),
        scenery_roughness=float(scenery_roughness),
        table=CdrfTable.build(*table_size),
        egg_tints=egg_tints,
        key_gain=float(light_intensities[0]) / KEY_INTENSITY,
    )
    kinds = {lib.kind for aggregate in aggregates for lib in aggregate.libraries}
    unknown = sorted(set(settings.presets) - kinds)
    if unknown:  # a misspelt kind changed nothing, silently
        raise ValueError(
            f"presets: {', '.join(repr(k) for k in unknown)} names no element kind of this scene; "
            f"its kinds are {', '.join(sorted(kinds))}"
        )
    return shade_scene(list(aggregates), list(scenery or []), settings, list(filling or []))
