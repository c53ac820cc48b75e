"""A shaded scene as a Mitsuba 3 scene (``scalar_rgb``, headless) and its denoised render — SPEC §4 preview.

The path tracer does the lighting, so surfaces get their materials, not the baked CDRF colours:

- translucent materials (``subsurface`` > 0: rice, the ikura yolk, shaved ice) are Mitsuba's ``principledthin`` with
  diffuse transmission ``subsurface × cdrf.translucency(σ)`` per vertex (shaved ice: ``subsurface`` on every vertex,
  a thin diffuser, as principledthin's ``diff_trans`` = 2 × ``subsurface``: it passes on half its ``diff_trans``),
  σ = σ₀|κ| the CDRF kernel width the shade node stored: the CDRF (eq. 7–9) evaluated in the BSDF
  as light passing through the grain, so strongly curved, wet parts glow past the terminator; sheen for the water
  film, and its clearcoat as a share of the surface rendered by ``principled`` (``coat_share``; principledthin has
  no coat lobe; shaved ice has no such share: its coat is the key's glints alone);
- transmissive materials (``transmission`` ≥ 0.5: the ikura membrane) are (rough) dielectrics
  whose transmittance per crossing is √``subsurface_color`` (two crossings give that colour): the yolk
  shows through the orange egg;
- the rest (the bowl's glaze) is ``principled`` with its clearcoat.

With ``subsurface`` on (the default), light goes under the skin for real (Mitsuba's ``volpath``): each closed
element of rice and each ikura yolk is a homogeneous scattering medium, the yolk's behind a dielectric boundary,
the grain's behind its wet film, which passes light unbent and reflects in a pass of its own (``medium``,
``boundary_bsdf``, ``highlight_dict``); each shaved-ice flake (a tuft of finer shavings in air, no skin of its own)
is one behind no boundary at all (``null``). The medium's mean free path and single-scattering albedo come from the
material's principled subsurface radius and colour (G Table 3) by the random-walk mapping of Chiang, Kutz and
Burley 2016, the one Blender's Cycles uses for the same parameters, so both renderers read the same numbers.
Rice's radius and colour follow its water content (``shading.materials.rice_material``; G fig. 3.1.2.1: wetter
is whiter and more translucent); no measured values for cooked rice are published: at 24 % water its mean free
path (≈ 1.65 mm in red) and albedo (≥ 0.99) match the starchy stand-in, potato (Jensen et al. 2001, table 2:
σ′s = 0.68, 0.70, 0.55 mm⁻¹, σa = 0.0024, 0.0090, 0.12 mm⁻¹). The CDRF stays on the surface: in the baked
vertex colours of the exported files and, with ``subsurface`` off, as the per-vertex diffuse transmission.

Light: a procedural studio (``studio``): a softbox key along the shade node's key light, a fill two stops under it
on the camera's side, a rim light behind the subject, a dim ambient and a matte seamless backdrop; the camera is a
thin lens focused on the front of the subject. The key's small bright core (``HIGHLIGHT_ANGLE``) is a specular-only
light, as a photographer sets a strip light for the glints: it is rendered in a pass of its own, one bounce, every
surface reflecting only with its gloss (its clear coat, or the skin of a transmissive element: Fresnel at its IOR),
through a pinhole, each glint then spread over the thin lens's circle of confusion at its depth (``defocus``,
``bokeh``: smooth bokeh, where 2 spp through the lens gave an out-of-focus glint as a few dots), and added after
denoising. In the denoised path-traced pass a glint is a few bright samples among dark ones, which the denoiser
reads as noise and erases (``benchmarks/bench_preview.py --highlights``: highlight energy 0 after OIDN); the
one-bounce pass of a smooth or glossy reflection has no such noise and needs no denoising. Left out of the
path-traced pass, the core does not add caustics through the eggs (found only by chance: fireflies). Mitsuba's
``aov`` integrator gives albedo and shading normals in a second, cheaper pass (1 spp, ``GUIDE_SPP``); Intel Open
Image Denoise (``pyoidn``) uses them as guides. The box reconstruction filter keeps pixels independent (what OIDN
expects) and makes the render bit-reproducible: image blocks do not overlap, so the order threads finish in cannot
change a sum. Meshes go to Mitsuba as binary PLY files in a temporary folder, one per material (its PLY loader is
~50× faster than filling ``mi.Mesh`` buffers from Python).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..shading.materials import PROPS
from ..values import Material, ShadedScene
from . import studio
from .look import (
    TRANSMISSIVE,
    boundary_roughness,
    crossing_tint,
    has_film,
    has_skin,
    is_volumetric,
    medium_coefficients,
)

# the light is a studio (``studio``: softbox key, fill, rim, seamless backdrop, thin lens); ``studio_description``
# gives it as numbers to the Blender side-by-side script (``tools/blender_side_by_side.py``)
EXPOSURE = 1.5  # linear scale before the tone curve: lit white rice (key + sky) near the knee
KNEE = 0.75  # the tone curve is linear below this and rolls off above it (white rice keeps its gloss, not clipped)
MAX_DEPTH = 10  # path length: light through the egg (membrane, yolk, membrane) and a few grains of rice
# path length in a heap of ice flakes: light scatters many times in each flake's medium (every collision counts)
# and walks through tens of flakes before it comes back out of the heap (why shaved ice is white); at MAX_DEPTH the
# walk was cut off and the ice rendered grey. Kakigori's mound, all plain ice, linear luminance of its pixels against
# the same mound in white diffuse (benchmarks/bench_preview.py --ice, 240 × 180, 8 spp): as a medium
# behind no skin 0.69 at depth 10, 0.99 at 32, 1.10 at 64, 1.11 at 128 and 256 (converged); as the thin diffuser
# (subsurface off) 0.98, 1.33, 1.53, 1.82, 1.85. Russian roulette ends the paths that carry little.
MAX_DEPTH_FLAKES = 128
# the key's bright core (a specular-only light, ``highlight_dict``): angular radius (rad) and radiance. 0.12 rad
# makes a glint ≈ 1–2 px across on a 4.5 mm egg in the main job's 1280 × 720 frame; the radiance puts it above
# the tone curve's knee on a clear skin (Fresnel ≈ 0.023 at normal incidence for IOR 1.36: 0.023 × 60 × 1.5 ≈ 2)
HIGHLIGHT_ANGLE = 0.12
HIGHLIGHT_RADIANCE = 60.0
# the glints' pass is one bounce: samples for antialiased edges, not for converging light. 4 (was 8): 15.8 → ≈ 8 CPU s
# of the main job's preview (benchmarks/bench_preview.py --budget; docs/accuracy.md, "Preview cost"); 2 (issue 27):
# ≈ 1.8 CPU s less, the glints as sharp, a little thinner at 6× zoom, no difference seen at 1:1. Enough at any depth:
# the pass is sharp (a pinhole) and the lens's blur comes after (``defocus``); through the lens, 2 spp gave an
# out-of-focus glint's disc as a few dots (a pixel of a 6.5-px disc sees a 1–3 px glint from ≈ 1–2 % of the
# aperture: 10 % noise at ≈ 7,000 spp; docs/look.md, "Bokeh, not dots")
HIGHLIGHT_SPP = 2
# the film pass (``highlight_dict`` with ``film``: rice's sheen, the softboxes in its rough lobe) samples a light
# at every sample; 8 a pixel leave its broad sheen smooth, added after the denoiser as the glints are
FILM_SPP = 8
# the glints' pass renders only the window of the film where a glint can be (``glints_window``): the subject's hull
# widened by the lens's blur and this many pixels. On the main job 58 % of the frame, 2.3–2.4 → 1.6 CPU s, every
# glint pixel of the whole-frame pass inside it (3–4 px from its edges at the bowl's rim)
GLINTS_MARGIN = 4
# the glints' blur (``defocus``) needs each pixel's depth through the pinhole: a 1-spp aov pass over the glints'
# scene (the aov integrator around the glints' own path integrator cost ≈ 2–3 CPU s more on the main job than the two)
DEPTH_AOV = "distance:depth"
COAT_SHARE_MAX = 0.3  # at most this share of a translucent surface is the coated lobe (the rest transmits)
ALBEDO_AOV = "albedo:albedo,nn:sh_normal"
VARIANT = "scalar_rgb"  # Mitsuba's scalar CPU RGB variant, which every description and render here uses
SAMPLER = "independent"  # multijitter, orthogonal, ldsampler: within ±1 dB after OIDN at 8 spp (and round spp)
# OIDN's filter quality. On the CPU "balanced" gives the same bits as "high" (its own network is for GPUs); "fast"
# saves ≈ 1.4 of its 2.8 CPU s on the main job but the frame moves 32.1 dB / SSIM 0.956 from high's (eggs window
# against 256 spp: −0.07 dB, −0.003 SSIM; docs/accuracy.md, "Preview cost"): high stays
DENOISE_QUALITY = "high"
# the guides need edges, not converged light: a cheap pass of their own. 1 (was 2, before that 4: 5.9 CPU s): ≈ 0.9
# CPU s less on the main job; in the eggs window against 256 spp 17.89 dB / SSIM 0.374 at 1, 17.86 / 0.374 at 2 (4
# seeds); the whole frame against the 2-spp guides' 42.2 dB / SSIM 0.993, no difference seen at 2× zoom (issue 27;
# docs/accuracy.md, "Preview cost"). Mitsuba's aov integrator around the volpath one (colour and guides in one
# pass) cost more, not less: 32.7 CPU s against 22.4 + 1.9 for the two passes, and other colour bits
GUIDE_SPP = 1
GUIDE_PASSES = 1  # guide passes averaged into the denoiser's albedo and normals (``guide_layers``)
CLEAN_AUX = False  # tell OIDN its guides are noise-free (``denoise``)
# path length with media: every scattering event inside a grain is a vertex of the path, and light that lights a
# heap of grains crosses many of them (and reflects inside them). A 3 mm grain at 15 % water is 3–6 mean free
# paths thick with albedo ≈ 0.99; at 32 the walks through the heap were cut off and the rice darkened (rice bowl
# draft, CIELAB L* of the rice's pixels: 73.7 at 32, 80.4 at 64; docs/look.md, "Warm white rice")
MAX_DEPTH_MEDIA = 64
# Russian roulette after this many bounces (Mitsuba's default). From the first bounce (1) the image pass cost ≈ 15 %
# less per sample on the main job but the eggs window lost 0.1–0.2 dB at the same samples: no better per CPU second,
# so 5 stays (issue 27; docs/accuracy.md, "Preview cost")
RR_DEPTH = 5


@dataclass(frozen=True)
class Camera:
    """An orbit camera aimed at the subject, distance chosen to fit its points with room around (``look_at``)."""

    elevation: float  # degrees above the horizon
    azimuth: float  # degrees, 0 = looking along +y, 90 = along −x
    fov: float  # degrees, horizontal
    margin: float  # share of the half-frame left free around the subject on its tightest side
    f_stop: float = 0.0  # the thin lens's f-number (full-frame equivalent, ``studio.aperture_radius``); 0: pinhole
    focus: float = 0.25  # the plane in focus: this quantile of the subject's depths (``studio.focus_distance``)
    offset: tuple[float, float] = (0.0, 0.0)  # where the subject's centre sits, in half-frames right and up


@dataclass(frozen=True)
class Crop:
    """A window of the film in pixels (the benchmark renders its reference in one)."""

    x: int
    y: int
    width: int
    height: int


def path_depth(scene: ShadedScene, subsurface: bool = False) -> int:
    """The path tracer's longest path: ``MAX_DEPTH_FLAKES`` where the scene has ice (a heap of thin diffusers
    that pass light from flake to flake, many flakes deep), ``MAX_DEPTH_MEDIA`` where light scatters inside
    elements (``subsurface``), else
    ``MAX_DEPTH`` (eggs and rice end paths sooner; the longer cap costs there without changing much)."""
    from ..shading.materials import is_ice

    if any(is_ice(m) for m in scene.materials):
        return MAX_DEPTH_FLAKES
    if subsurface and any(is_volumetric(m) for m in scene.materials):
        return MAX_DEPTH_MEDIA
    return MAX_DEPTH


def _rgb(value) -> dict:
    return {"type": "rgb", "value": [float(c) for c in value]}


def alpha(roughness: float) -> float:
    """Microfacet α from a principled roughness (Disney: α = roughness²)."""
    return float(roughness) ** 2


def material_bsdf(material: Material, translucent_vertices: bool) -> dict:
    """Mitsuba BSDF for a principled parameter set (see the module note for the three families)."""
    from ..shading.materials import is_ice

    if material.transmission >= TRANSMISSIVE:
        tint = crossing_tint(material) * material.transmission
        a = alpha(material.transmission_roughness)
        bsdf = {"type": "dielectric", "int_ior": float(material.ior), "ext_ior": float(material.exterior_ior)}
        if a > 1e-3:
            bsdf = {**bsdf, "type": "roughdielectric", "alpha": a, "distribution": "ggx"}
        return {**bsdf, "specular_transmittance": _rgb(tint)}
    if material.subsurface > 0:
        diff_trans = (
            {"type": "mesh_attribute", "name": "vertex_trans"}
            if translucent_vertices
            else float(min(1.0, material.subsurface / (1.0 - coat_share(material))))
        )
        if is_ice(material):  # principledthin passes on diff_trans / 2 of its diffuse light: the share is subsurface
            diff_trans = float(min(2.0, 2.0 * material.subsurface))
        thin = {
            "type": "principledthin",
            "base_color": _rgb(material.base_color),
            "roughness": float(material.roughness),
            "diff_trans": diff_trans,
            "spec_trans": float(material.transmission),
            "eta": float(material.ior),
            "sheen": float(material.sheen),
            "sheen_tint": float(material.sheen_tint),
        }
        # shaved ice: no opaque coated share (it lit every soaked flake's rim and hid its translucency); its wet
        # coat is the thin surface's own gloss and the key's glints (``gloss``)
        if material.clearcoat <= 0 or is_ice(material):
            return thin
        # principledthin has no clearcoat lobe: a share (``coat_share``) of the surface is principled with the
        # coat; the thin share's transmission is raised to keep the whole surface's (``_shapes``).
        coated = {**_principled(material), "clearcoat": 1.0}
        return {"type": "blendbsdf", "weight": coat_share(material), "bsdf_0": thin, "bsdf_1": coated}
    if material.specular <= 0 and material.clearcoat >= 1 and material.metallic <= 0:
        return coat_bsdf(material)
    return _principled(material)


def coat_bsdf(material: Material) -> dict:
    """A colour seen only diffusely under one dielectric coat (a glaze, a lacquer: ``materials.coated``): Mitsuba's
    plastic, a diffuse body under a GGX interface at the coat's IOR and roughness, as Cycles' coat over its base.
    Disney's coat in ``principled`` is GTR1, whose long tails spread a glaze's sharp reflections of the studio into
    a haze over the bowl (docs/look.md, "Noise or a different picture")."""
    bsdf = {"type": "plastic", "diffuse_reflectance": _rgb(material.base_color), "int_ior": float(material.ior)}
    a = alpha(material.clearcoat_roughness)
    return {**bsdf, "type": "roughplastic", "alpha": a, "distribution": "ggx"} if a > 1e-3 else bsdf


def medium(material: Material) -> dict:
    """Mitsuba homogeneous medium inside a volumetric element (``random_walk_coefficients``), isotropic phase.

    Every element scatters the same in every channel, at the mean of the channels' σt; its colour is in the albedo
    alone (rice, the yolk, and syrup in shaved ice, whose red is absorption). Scattering in starch is nearly grey
    (potato, Jensen et al. 2001: σ′s = 0.68, 0.70, 0.55 mm⁻¹; the colour is in σa); a σt per channel made volpath
    sample the distance in one channel and weight the others, colour noise that the denoiser left as opal patches of
    green, pink and blue on every grain (docs/look.md, "Warm white rice")."""
    sigma_t, single = medium_coefficients(material)
    return {
        "type": "homogeneous",
        "albedo": _rgb(single),
        "sigma_t": _rgb(np.ones(3)),  # Mitsuba reads an RGB as a reflectance in [0, 1]: the scale carries the unit
        "scale": sigma_t,
        "phase": {"type": "isotropic"},
        # light sampling from inside only through a null boundary (shaved ice, rice's film): a dielectric one blocks
        # every shadow ray cast from within (volpath counts light only through a null boundary), so each was a
        # wasted ray; light still reaches the medium by the phase function's own direction and the boundary's
        # refraction
        "sample_emitters": not has_skin(material),
    }


def boundary_bsdf(material: Material) -> dict:
    """The dielectric skin of a volumetric element, clear, so the medium alone colours the light, and smooth.
    Mitsuba's rough dielectric is single-scattering microfacets: it loses the energy of light bouncing between
    facets at every crossing, inside as well as out, and light under a skin meets it many times. Under a white
    furnace a rice grain at its film's roughness (α 0.11) returned 0.93, a smooth skin 1.00, and Cycles' multiscatter
    GGX skin in the add-on conserves it (docs/look.md, "The skin over a medium conserves energy"). The skin's
    roughness stays in its glints (``gloss``) and in the files (``look.boundary_roughness``).

    Rice's skin is a film (``look.has_film``): ``null`` here, the film's reflection a pass of its own
    (``highlight_dict`` with ``film``). Dry or damp shaved ice has none (``null``; soaked through,
    ``materials.is_wet``, it has one): a flake stands
    for a tuft of shavings 0.05–0.1 mm thin with air between, whose pores open to the air; its countless small
    interfaces are the medium's scattering, not one skin. Behind a dielectric skin the light that crossed a flake
    unscattered was refracted and reflected as by glass, and the heap read as grey glass (docs/look.md,
    "Kakigori"); the wet gloss of soaked ice is its clear coat (the key's glints, ``gloss``)."""
    if not has_skin(material):
        return {"type": "null"}
    return {"type": "dielectric", "int_ior": float(material.ior), "ext_ior": float(material.exterior_ior)}


def diffuse_transmission(material: Material, sigma: np.ndarray) -> np.ndarray:
    """Per-vertex ``diff_trans`` of a translucent material: ``subsurface × cdrf.translucency(σ)`` (SPEC §4 eq. 7–9
    as light through the grain), raised on the uncoated share so the whole surface transmits that much."""
    from ..shading.cdrf import translucency

    weight = material.subsurface * translucency(sigma) / (1.0 - coat_share(material))
    return np.clip(weight, 0.0, 1.0)


def coat_share(material: Material) -> float:
    """Share of a translucent surface rendered with the clearcoat lobe (the rest carries the transmission)."""
    return float(np.clip(material.clearcoat, 0.0, COAT_SHARE_MAX))


DISNEY_COAT = 0.25  # Mitsuba's principled coat lobe is Disney's: clearcoat × 0.25 × Schlick(F0 0.04) (principled.cpp)


def _principled(material: Material) -> dict:
    """Mitsuba's principled BSDF for a material's parameters. Its coat follows Disney (Burley 2012), whose lobe is
    scaled by ``DISNEY_COAT``: a coat of weight 1 reflected a quarter of Fresnel (F0 0.04 at IOR 1.5), where
    Cycles' coat and glTF's KHR_materials_clearcoat reflect all of it. The weight passed is the material's over
    ``DISNEY_COAT``, so a coat reflects the studio as Fresnel says in both renderers (docs/look.md; a glaze or a
    lacquer is ``coat_bsdf``). A material with no specular of its own (``specular`` 0) gets Mitsuba's
    ``specular`` 0 in place of its IOR (Fresnel 0: Blender's Specular IOR Level 0, glTF's specularFactor 0)."""
    own = {"eta": float(material.ior)} if material.specular > 0 else {"specular": 0.0}
    return {
        "type": "principled",
        "base_color": _rgb(material.base_color),
        "roughness": float(material.roughness),
        "metallic": float(material.metallic),
        "sheen": float(material.sheen),
        "sheen_tint": float(material.sheen_tint),
        "clearcoat": float(material.clearcoat) / DISNEY_COAT,
        "clearcoat_gloss": float(1.0 - material.clearcoat_roughness),
        "spec_trans": float(material.transmission),
        **own,
    }


def hull_vertices(points: np.ndarray) -> np.ndarray:
    """The points on their convex hull (all of them when they are too few or flat for one)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        return points[ConvexHull(points).vertices]
    except (QhullError, ValueError):
        return points


def look_at(points: np.ndarray, camera: Camera, aspect: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(origin, target): seen from the camera's elevation and azimuth, the subject's ``points`` centred in the frame
    and as large as leaves ``camera.margin`` of the half-frame free on its tightest side (``aspect`` = width /
    height), then, with ``camera.offset``, the camera moved parallel to the film so that the subject's centre sits
    that many half-frames right and up (−1/3, 0: on the left third line); the fit leaves room for the move.
    Derived from the points, so the framing follows any change of the scene (a bigger bowl, a --set). Only
    the convex hull's vertices matter (a projected coordinate x / depth is linear-fractional, so its extremes over
    the points are hull vertices): a subsample could miss the rim's outermost vertex and put it past the margin."""
    points = hull_vertices(np.asarray(points, np.float64))
    el, az = np.radians(camera.elevation), np.radians(camera.azimuth)
    view = np.array([np.sin(az) * np.cos(el), -np.cos(az) * np.cos(el), np.sin(el)])  # towards the camera
    right = np.cross(-view, [0.0, 0.0, 1.0])
    right = right / np.linalg.norm(right) if np.linalg.norm(right) > 1e-9 else np.array([1.0, 0.0, 0.0])
    up = np.cross(right, -view)
    shift_x, shift_y = (float(c) for c in camera.offset)
    tan_x = np.tan(np.radians(camera.fov) / 2)
    tan_y = tan_x / aspect
    free_x = max(1.0 - camera.margin - abs(shift_x), 1e-3)
    free_y = max(1.0 - camera.margin - abs(shift_y), 1e-3)
    target = 0.5 * (points.min(axis=0) + points.max(axis=0))
    for _ in range(4):  # recentre on the projected extent, then fit again
        rel = points - target
        x, y, z = rel @ right, rel @ up, rel @ view
        distance = float(np.max(z + np.maximum(np.abs(x) / (free_x * tan_x), np.abs(y) / (free_y * tan_y))))
        distance = max(distance, float(z.max()) + 1e-6 * float(np.ptp(points, axis=0).max() + 1.0))
        depth = distance - z
        u, v = x / (depth * tan_x), y / (depth * tan_y)
        shift = 0.5 * (u.max() + u.min()) * tan_x * right + 0.5 * (v.max() + v.min()) * tan_y * up
        target = target + distance * shift
    rel = points - target
    x, y, z = rel @ right, rel @ up, rel @ view
    distance = float(np.max(z + np.maximum(np.abs(x) / (free_x * tan_x), np.abs(y) / (free_y * tan_y))))
    target = target - distance * (shift_x * tan_x * right + shift_y * tan_y * up)
    return target + distance * view, target


def framed_points(scene: ShadedScene) -> np.ndarray:
    """The vertices the camera frames and focuses on: every mesh's but a prop's (``materials.PROPS``: chopsticks on
    the table reach past the frame as they would in a food photograph, and do not shrink the dish in it)."""
    return np.concatenate(
        [
            m.vertices
            for m, k in zip(scene.meshes, scene.material_of)
            if len(m.faces) and scene.materials[k].name not in PROPS
        ]
    )


def _shapes(scene: ShadedScene, folder: Path, subsurface: bool = False) -> tuple[dict, np.ndarray]:
    """One PLY shape per material (written into ``folder``; key ``shape_<material index>``) and the scene's
    vertices (what the camera frames and focuses on); with ``subsurface``, the volumetric materials' shapes carry their
    medium inside a dielectric boundary. Where a mesh carries its own transmittance per vertex
    (``ShadedScene.transmittance``: an egg's membrane, paler over its eye), its shape's skin reads each vertex's
    (√ per crossing, as ``crossing_tint``; Mitsuba's ``vertex_color``)."""
    from ..shading.materials import is_ice
    from .mesh_files import stacked, write_ply

    shapes = {}
    seen = []
    for index, material in enumerate(scene.materials):
        members = [k for k, m in enumerate(scene.material_of) if m == index and len(scene.meshes[k].faces)]
        if not members:
            continue
        meshes = [scene.meshes[k] for k in members]
        vertices, faces = stacked(meshes)
        normals = np.concatenate(
            [m.normals if m.normals is not None else np.zeros((len(m.vertices), 3)) for m in meshes]
        )
        colors = np.tile(material.base_color, (len(vertices), 1))
        own = [scene.vertex_transmittance(k) for k in members]
        joined = material.transmission >= TRANSMISSIVE and any(t is not None for t in own)
        if joined:  # each vertex's own skin colour
            whole = crossing_tint(material) * material.transmission
            colors = np.concatenate(
                [
                    np.tile(whole, (len(m.vertices), 1)) if t is None else np.sqrt(t) * material.transmission
                    for t, m in zip(own, meshes)
                ]
            )
        volume = subsurface and is_volumetric(material)
        per_vertex = (
            not volume
            and bool(scene.cdrf_sigma)
            and material.subsurface > 0
            and material.transmission < TRANSMISSIVE
            and not is_ice(material)
        )
        trans = None
        if per_vertex:
            sigma = np.concatenate([scene.cdrf_sigma[k] for k in members])
            trans = diffuse_transmission(material, sigma)
        path = folder / f"material_{index}.ply"
        write_ply(path, vertices, faces, normals, colors, trans)
        bsdf = boundary_bsdf(material) if volume else material_bsdf(material, per_vertex)
        if joined:
            bsdf = {**bsdf, "specular_transmittance": {"type": "mesh_attribute", "name": "vertex_color"}}
        shapes[f"shape_{index}"] = {"type": "ply", "filename": str(path), "bsdf": bsdf, "face_normals": False}
        if volume:
            shapes[f"shape_{index}"]["interior"] = medium(material)
        if material.name not in PROPS:  # a prop beside the dish is not what the camera frames and focuses on
            seen.append(vertices)
    if not shapes:
        raise ValueError("scene: no mesh with faces to render")
    return shapes, np.concatenate(seen)


def gloss(material: Material, skin: bool = False) -> tuple[float, float]:
    """(weight, roughness) of a surface's glossy reflection, which the glints' pass renders: the dielectric skin
    over a medium where the preview renders one (``skin``: weight 1 at ``boundary_roughness``), else its clear
    coat, else the skin of a transmissive element (weight 1 at its transmission roughness), else none (weight 0).

    A skin over a medium is an interface: it reflects Fresnel's share of the key's core, as it reflects the rest of
    the studio in the path-traced pass and as Cycles' transmission lobe does (the add-on's skin). At the coat's
    weight (0.31 for rice at 15 % water) the rice's glints were a third of what the same skin reflects
    (docs/look.md, "Cooked rice: wet, milky, warm")."""
    if skin:
        return 1.0, boundary_roughness(material)
    if material.clearcoat > 0:
        return float(material.clearcoat), float(material.clearcoat_roughness)
    if material.transmission >= TRANSMISSIVE:
        return 1.0, float(material.transmission_roughness)
    return 0.0, 1.0


def specular_bsdf(material: Material, skin: bool = False) -> dict:
    """Reflection only, as the glints' pass sees a surface: Fresnel at the material's IOR times its gloss weight,
    a microfacet lobe at the gloss roughness (Mitsuba's (rough)plastic with no diffuse part); black when matte.
    ``skin``: the surface is a dielectric skin over a medium (``gloss``)."""
    weight, rough = gloss(material, skin)
    if weight <= 0:
        return {"type": "diffuse", "reflectance": _rgb((0.0, 0.0, 0.0))}
    bsdf = {
        "type": "plastic",
        "diffuse_reflectance": _rgb((0.0, 0.0, 0.0)),
        "specular_reflectance": _rgb((weight, weight, weight)),
        "int_ior": float(material.ior),
        "ext_ior": float(material.exterior_ior),
    }
    a = alpha(rough)
    return {**bsdf, "type": "roughplastic", "alpha": a, "distribution": "ggx"} if a > 1e-3 else bsdf


def glints_core(description: dict) -> tuple[np.ndarray, float]:
    """Centre and radius of the key's bright core (the glints' light): a sphere at the key softbox's centre,
    ``HIGHLIGHT_ANGLE`` across as seen from the subject."""
    frame = np.array(description["key"]["to_world"].matrix, np.float64)
    distance = float(np.linalg.norm(frame[:3, 0])) / np.tan(studio.KEY_ANGLE)
    return frame[:3, 3], float(distance * np.tan(HIGHLIGHT_ANGLE))


def glints_window(
    set_up: Stage, camera: Camera, width: int, height: int, core: tuple[np.ndarray, float], crop: Crop | None = None
) -> Crop | None:
    """The part of the film (within ``crop``, else the whole) where a glint can be: the subject's hull projected,
    each point widened by the thin lens's circle of confusion at its depth, and the key's bright core (``core``:
    centre, radius) where it is in front of the camera, with ``GLINTS_MARGIN`` pixels more. Outside it the glints'
    pass sees only the black backdrop. None when a point is behind the camera (then the whole film)."""
    forward = -set_up.view
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right = right / np.linalg.norm(right)
    up = np.cross(right, forward)
    tan_x = np.tan(np.radians(camera.fov) / 2)
    tan_y = tan_x * height / width
    centre, radius = core
    corners = np.asarray(centre) + radius * np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)])
    if np.any((corners - set_up.origin) @ forward <= 0):
        corners = np.empty((0, 3))  # the core is behind the camera: never in the picture
    rel = np.concatenate([set_up.hull, corners]) - set_up.origin
    depth = rel @ forward
    if np.any(depth <= 0):
        return None
    aperture, focus = studio.aperture_radius(camera.fov, camera.f_stop), set_up.focus_distance
    blur = studio.blur_radius(depth, aperture, focus, tan_x, width)
    x = (1.0 + (rel @ right) / (depth * tan_x)) * width / 2
    y = (1.0 - (rel @ up) / (depth * tan_y)) * height / 2
    frame = crop or Crop(0, 0, width, height)
    x0 = max(frame.x, int(np.floor((x - blur).min())) - GLINTS_MARGIN)
    y0 = max(frame.y, int(np.floor((y - blur).min())) - GLINTS_MARGIN)
    x1 = min(frame.x + frame.width, int(np.ceil((x + blur).max())) + GLINTS_MARGIN)
    y1 = min(frame.y + frame.height, int(np.ceil((y + blur).max())) + GLINTS_MARGIN)
    if x1 <= x0 or y1 <= y0:  # no glint can fall in the film: one black pixel of it
        return Crop(frame.x, frame.y, 1, 1)
    return Crop(x0, y0, x1 - x0, y1 - y0)


def backdrop_gloss(backdrop: dict) -> dict | None:
    """What the backdrop reflects of the key's bright core (the glints' pass): the table's oiled sheen, its
    principled lobe over a black base, or None for the paper sweep, which is matte. Cycles' table, glossy, showed
    the core as a broad sheen on the boards in front of the bowl where the preview's black table showed none
    (docs/look.md, "Noise or a different picture")."""
    bsdf = backdrop["bsdf"]
    return {**bsdf, "base_color": _rgb((0.0, 0.0, 0.0))} if bsdf["type"] == "principled" else None


def highlight_dict(scene: ShadedScene, description: dict, window: Crop | None = None, film: bool = False) -> dict:
    """The glints' pass of a scene description (``scene_dict``): the same shapes (PLY files) and camera, every
    surface reflecting only its gloss (``specular_bsdf``, ``backdrop_gloss``), lit by the key's bright core
    alone (``HIGHLIGHT_ANGLE``, ``HIGHLIGHT_RADIANCE``), paths of one bounce; rendered in ``window`` of the film
    if given (``glints_window``), through a pinhole at the lens's centre, sharp at every depth, for ``defocus`` to
    blur as the thin lens would (with ``DEPTH_AOV``'s distances).

    ``film``: the film pass. The films over media (``look.has_film``: rice) reflect the studio's softboxes (key,
    fill, rim) and nothing else does: the path-traced pass passes light through a film unbent and reflects none
    of it (``boundary_bsdf``), so the film's sheen is this one-bounce pass, where its rough lobe samples the
    softboxes directly, every sample, and no denoiser blurs it."""
    black = {"type": "diffuse", "reflectance": _rgb((0.0, 0.0, 0.0))}
    shapes = {}
    for key, shape in description.items():
        if key.startswith("shape_"):
            material = scene.materials[int(key.removeprefix("shape_"))]
            skin = "interior" in shape and (has_skin(material) or has_film(material))
            bsdf = specular_bsdf(material, skin)
            if film and not ("interior" in shape and has_film(material)):
                bsdf = black
            shapes[key] = {k: v for k, v in shape.items() if k != "interior"} | {"bsdf": bsdf}
    centre, radius = glints_core(description)
    sensor = {k: v for k, v in description["sensor"].items() if k not in ("aperture_radius", "focus_distance")}
    sensor["type"] = "perspective"  # the lens's blur is ``defocus``'s, after the pass
    sensor["sampler"] = {"type": SAMPLER, "sample_count": min(sensor["sampler"]["sample_count"], HIGHLIGHT_SPP)}
    if window is not None:
        sensor["film"] = sensor["film"] | {
            "crop_offset_x": window.x,
            "crop_offset_y": window.y,
            "crop_width": window.width,
            "crop_height": window.height,
        }
    if film:
        lights = {name: description[name] for name in studio.LIGHTS}
        backdrop = black
    else:
        core = {"type": "area", "radiance": {"type": "rgb", "value": scene.key_gain * HIGHLIGHT_RADIANCE}}
        lights = {"key": {"type": "sphere", "center": centre.tolist(), "radius": radius, "emitter": core}}
        backdrop = backdrop_gloss(description["backdrop"]) or black
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": sensor,
        **lights,
        "backdrop": {**description["backdrop"], "bsdf": backdrop},
        **shapes,
    }


def defocus(glints: np.ndarray, distance: np.ndarray, sensor: dict, width: int, height: int, frame: Crop) -> np.ndarray:
    """The glints' pass (``highlight_dict``: sharp, through a pinhole; linear RGB, and each pixel's distance along
    its ray, 0 where nothing is, in the ``frame`` of the ``width`` × ``height`` film) as the scene's thin lens
    (``sensor``) shows it: every glint spread over a uniform disc, its circle of confusion at its depth
    (``bokeh.scatter_discs``): the smooth bokeh that the lens converges to, where two samples a pixel through the
    lens gave an out-of-focus glint as a few bright dots (docs/look.md, "Bokeh, not dots"). A pinhole sensor: the
    pass as it is."""
    if sensor["type"] != "thinlens":
        return glints
    from .bokeh import scatter_discs

    tan_x = np.tan(np.radians(sensor["fov"]) / 2)
    tan_y = tan_x * height / width
    x = (2.0 * (np.arange(frame.x, frame.x + frame.width) + 0.5) / width - 1.0) * tan_x
    y = (1.0 - 2.0 * (np.arange(frame.y, frame.y + frame.height) + 0.5) / height) * tan_y
    depth = distance / np.sqrt(1.0 + x[None, :] ** 2 + y[:, None] ** 2)  # along the optical axis
    aperture, focus = float(sensor["aperture_radius"]), float(sensor["focus_distance"])
    radius = studio.blur_radius(np.where(depth > 0, depth, focus), aperture, focus, tan_x, width)
    return scatter_discs(np.ascontiguousarray(glints, np.float32), depth.astype(np.float32), radius.astype(np.float32))


def guide_albedo(material: Material) -> tuple[float, float, float]:
    """The colour the denoiser's albedo guide gives a surface: what it looks like in white light. A transmissive
    or volumetric element's own albedo AOV is its skin's Fresnel reflection, ≈ 0.03 grey for eggs and rice alike,
    so OIDN could not tell a red egg from the white rice beside it and spread the eggs' red over the rice between
    them (docs/look.md, "Side by side with Blender"); it gets the colour light keeps through it (eggs) or scatters
    back out of it (rice, yolks, ice), as OIDN asks of dielectrics, and the rest their base colour."""
    if material.transmission >= TRANSMISSIVE or is_volumetric(material):
        return tuple(float(c) for c in material.subsurface_color)
    return tuple(float(c) for c in material.base_color)


def guides_with_albedo(aov: np.ndarray, loaded, scene: ShadedScene) -> np.ndarray:
    """The denoiser's guides (albedo, normal) from one ``aov`` pass over the loaded scene with its shape index:
    every pixel whose sample hit a described shape (``shape_<material>``) takes its material's ``guide_albedo``,
    the backdrop keeps its own. One sample a pixel (``GUIDE_SPP``) through the film's box filter, so each pixel's
    index names one shape; the same as rendering a matte copy of the scene, without loading its meshes again
    (3 s of the onigiri's preview)."""
    shapes = list(loaded.shapes())
    keys = [shape.id() for shape in shapes]  # Mitsuba's shape_index is 1 + the position here; 0 a miss
    table = np.full((len(keys) + 1, 3), np.nan, np.float32)
    for position, key in enumerate(keys):
        if key.startswith("shape_"):
            table[position + 1] = guide_albedo(scene.materials[int(key.removeprefix("shape_"))])
    index = np.clip(np.rint(aov[..., 6]).astype(np.int64), 0, len(keys))
    albedo = table[index]
    for position, (shape, key) in enumerate(zip(shapes, keys)):
        if key.startswith("shape_") and shape.has_attribute("vertex_color"):
            material = scene.materials[int(key.removeprefix("shape_"))]
            if material.transmission >= TRANSMISSIVE:  # a skin with its own colour per vertex: an egg's eye
                hit = index == position + 1
                faces = np.asarray(shape.faces_buffer(), np.int64).reshape(-1, 3)
                skin = np.asarray(shape.attribute_buffer("vertex_color"), np.float32).reshape(-1, 3)
                triangle = np.clip(np.rint(aov[..., 7][hit]).astype(np.int64), 0, len(faces) - 1)
                albedo[hit] = eye_albedo(skin[faces[triangle]].mean(axis=1), material)
    own = np.isnan(albedo[..., 0])
    albedo[own] = aov[..., 0:3][own]
    return np.concatenate([albedo, aov[..., 3:6]], axis=-1)


def guide_layers(loaded, scene: ShadedScene, seed: int) -> np.ndarray:
    """The denoiser's guides (albedo, normal; ``guides_with_albedo``), the mean of ``GUIDE_PASSES`` one-sample
    passes, each with its own seed (``seed`` × ``GUIDE_PASSES`` + pass)."""
    import mitsuba as mi

    guides = mi.load_dict({"type": "aov", "aovs": ALBEDO_AOV + ",si:shape_index,pi:prim_index"})
    total = None
    for index in range(GUIDE_PASSES):
        aov = np.asarray(mi.render(loaded, integrator=guides, seed=seed * GUIDE_PASSES + index, spp=GUIDE_SPP))
        layer = guides_with_albedo(np.asarray(aov, np.float32), loaded, scene)
        total = layer if total is None else total + layer
    return total / np.float32(GUIDE_PASSES)


def eye_albedo(skin: np.ndarray, material: Material) -> np.ndarray:
    """The albedo guide of a skin whose transmittance varies per vertex (``_shapes``: √ of the egg's colour there,
    times its transmission), as ``guide_albedo`` gives a whole egg: the colour light keeps through it, in and out.
    With the material's one colour the guide had no edge where the eye is, and OIDN at 3 spp smeared each egg's
    pale eye into the egg's own red (docs/look.md, "Ikura colour")."""
    return np.clip((skin / max(material.transmission, 1e-6)) ** 2, 0.0, 1.0).astype(np.float32)


def scene_dict(
    scene: ShadedScene,
    folder: Path,
    camera: Camera,
    width: int,
    height: int,
    spp: int,
    light_direction,
    crop: Crop | None = None,
    max_depth: int | None = None,
    subsurface: bool = False,
    ambient: float = studio.AMBIENT,
    setting: str = "sweep",
) -> dict:
    """The Mitsuba scene description; PLY files are written into ``folder``. ``max_depth``: the longest path
    (default ``path_depth``: by the scene's materials); ``subsurface``: media inside the volumetric elements, traced
    by ``volpath``; ``ambient``: radiance of the studio's uniform ambient; ``setting``: what the subject stands on
    (``studio.SETTINGS``: the seamless sweep, or a table of oak boards)."""
    import mitsuba as mi

    mi.set_variant(VARIANT)  # the description builds Mitsuba's transforms, which need a variant
    return _described(
        scene, folder, camera, width, height, spp, light_direction, crop, max_depth, subsurface, ambient, setting
    )[0]


def _described(
    scene: ShadedScene,
    folder: Path,
    camera: Camera,
    width: int,
    height: int,
    spp: int,
    light_direction,
    crop: Crop | None,
    max_depth: int | None,
    subsurface: bool,
    ambient: float,
    setting: str = "sweep",
) -> tuple[dict, Stage]:
    """``scene_dict`` and the ``Stage`` it set up."""
    import mitsuba as mi

    shapes, points = _shapes(scene, folder, subsurface)
    media = any("interior" in shape for shape in shapes.values())
    set_up = stage(points, camera, width / height, light_direction, scene.key_gain)
    film = {
        "type": "hdrfilm",
        "width": width,
        "height": height,
        "pixel_format": "rgb",
        "rfilter": {"type": "box"},
    }
    if crop is not None:
        film |= {"crop_offset_x": crop.x, "crop_offset_y": crop.y, "crop_width": crop.width, "crop_height": crop.height}
    sensor = {
        "type": "perspective",
        "fov": camera.fov,
        "fov_axis": "x",
        "to_world": mi.ScalarTransform4f().look_at(
            origin=set_up.origin.tolist(), target=set_up.target.tolist(), up=[0, 0, 1]
        ),
        "film": film,
        "sampler": {"type": SAMPLER, "sample_count": spp},
    }
    if camera.f_stop > 0:
        sensor |= {
            "type": "thinlens",
            "aperture_radius": studio.aperture_radius(camera.fov, camera.f_stop),
            "focus_distance": set_up.focus_distance,
        }
    description = {
        "type": "scene",
        "integrator": {
            "type": "volpath" if media else "path",
            "max_depth": max_depth or path_depth(scene, subsurface),
            "rr_depth": RR_DEPTH,
        },
        "sensor": sensor,
        "sky": {
            "type": "constant",
            "radiance": {"type": "rgb", "value": float(ambient)},
            "sampling_weight": float(np.pi * max(ambient, 1e-6)),
        },
        **{name: studio.light_dict(light, set_up.target) for name, light in set_up.lights.items()},
        "backdrop": (
            studio.table_dict(folder, set_up.target, set_up.radius, set_up.floor, set_up.view)
            if setting == "table"
            else studio.backdrop_dict(folder / "backdrop.ply", set_up.target, set_up.radius, set_up.floor, set_up.view)
        ),
        **shapes,
    }
    return description, set_up


@dataclass(frozen=True)
class Stage:
    """Where the camera stands and the studio around a subject (``stage``): what the preview renders and what the
    Blender side-by-side builds (``studio_description``)."""

    origin: np.ndarray  # the camera
    target: np.ndarray  # where it aims: the subject's centre as framed
    radius: float  # the subject's radius: half its bounding box's diagonal
    view: np.ndarray  # unit vector from the target towards the camera
    floor: float  # height of the backdrop's floor: just under the subject's lowest point
    focus_distance: float  # along the optical axis, to the plane in focus
    lights: dict  # name → studio.Light (key, fill, rim)
    hull: np.ndarray | None = None  # the subject's points on its convex hull (``hull_vertices``)


def stage(points: np.ndarray, camera: Camera, aspect: float, light_direction, key_gain: float = 1.0) -> Stage:
    """The camera fitted to the subject's ``points`` (``look_at``) and the studio's lights and backdrop around it;
    ``key_gain`` scales the key softbox (``ShadedScene.key_gain``)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    hull = hull_vertices(np.asarray(points, np.float64))
    origin, target = look_at(hull, camera, aspect)
    radius = 0.5 * float(np.linalg.norm(hi - lo))
    view = (origin - target) / np.linalg.norm(origin - target)
    return Stage(
        origin,
        target,
        radius,
        view,
        float(lo[2]) - 1e-3 * radius,
        studio.focus_distance(points, origin, target, camera.focus),
        studio.lights(target, radius, view, light_direction, key_gain),
        hull,
    )


def studio_description(
    scene: ShadedScene,
    camera: Camera,
    width: int,
    height: int,
    light_direction,
    ambient: float = studio.AMBIENT,
    setting: str = "sweep",
) -> dict:
    """The preview's camera, lens, lights, backdrop, exposure and path depth as plain numbers (JSON), for another
    renderer to build the same studio around the same scene (``tools/blender_side_by_side.py``)."""
    points = framed_points(scene)
    set_up = stage(points, camera, width / height, light_direction, scene.key_gain)
    vertices, faces, _ = studio.backdrop_mesh(set_up.target, set_up.radius, set_up.floor, set_up.view)
    backdrop = {"vertices": vertices.tolist(), "faces": faces.tolist(), "color": list(studio.BACKDROP_COLOR)}
    if setting == "table":  # the texture itself: ``studio.wood_png``, written beside the description by its reader
        corners = studio.table_corners(set_up.target, set_up.radius, set_up.floor, set_up.view)
        backdrop = {
            "vertices": corners.tolist(),
            "faces": [[0, 1, 2, 3]],
            "uv": studio.table_uv(set_up.radius).tolist(),
            "texture": "table.png",
            "roughness": studio.TABLE_ROUGHNESS,
        }
    key = set_up.lights["key"]
    key_distance = float(np.linalg.norm(key.center - set_up.target))
    return {
        "width": width,
        "height": height,
        "camera": {
            "origin": set_up.origin.tolist(),
            "target": set_up.target.tolist(),
            "fov": camera.fov,
            "f_stop": camera.f_stop,
            "aperture_radius": studio.aperture_radius(camera.fov, camera.f_stop),
            "focus_distance": set_up.focus_distance,
        },
        "ambient": float(ambient),
        "lights": {
            name: {"center": light.center.tolist(), "half_sizes": list(light.half_sizes), "radiance": light.radiance}
            for name, light in set_up.lights.items()
        },
        "target": set_up.target.tolist(),
        "glints": {
            "center": key.center.tolist(),
            "radius": key_distance * float(np.tan(HIGHLIGHT_ANGLE)),
            "radiance": scene.key_gain * HIGHLIGHT_RADIANCE,
        },
        "backdrop": backdrop,
        "exposure": EXPOSURE,
        "knee": KNEE,
        "max_depth": MAX_DEPTH_MEDIA,
    }


@dataclass(frozen=True)
class Layers:
    """A render's linear colour, the denoiser's guides and the glints (``highlight_dict``, added after denoising),
    float32 (height, width, 3) each."""

    color: np.ndarray
    albedo: np.ndarray
    normal: np.ndarray
    highlights: np.ndarray

    def noisy(self) -> np.ndarray:
        """The linear picture without denoising: path-traced colour plus glints."""
        return self.color + self.highlights

    def denoised(self) -> np.ndarray:
        """The linear picture: denoised path-traced colour plus glints (``denoise``)."""
        return denoise(self) + self.highlights


def render_layers(
    scene: ShadedScene,
    camera: Camera,
    width: int,
    height: int,
    spp: int,
    light_direction,
    seed: int = 0,
    crop: Crop | None = None,
    max_depth: int | None = None,
    subsurface: bool = False,
    ambient: float = studio.AMBIENT,
    setting: str = "sweep",
) -> Layers:
    """Path-traced linear colour with albedo and normal AOVs and the glints' pass; same inputs and seed ⇒ the same
    bits."""
    import tempfile

    import mitsuba as mi

    mi.set_variant(VARIANT)
    with tempfile.TemporaryDirectory(prefix="nodegraph_preview_") as folder:
        description, set_up = _described(
            scene,
            Path(folder),
            camera,
            width,
            height,
            spp,
            light_direction,
            crop,
            max_depth,
            subsurface,
            ambient,
            setting,
        )
        # optimize=False: Mitsuba's merging of identical objects made about one render in six differ from the
        # others in the same process (tests/export/test_preview.py); merging saves memory only (shared materials)
        loaded = mi.load_dict(description, optimize=False)
        image = np.asarray(mi.render(loaded, seed=seed), np.float32)
        aov = guide_layers(loaded, scene, seed)
        window = None  # the core's sheen on a glossy backdrop can fall anywhere on it: the whole film
        if backdrop_gloss(description["backdrop"]) is None:
            window = glints_window(set_up, camera, width, height, glints_core(description), crop)
        pinhole = mi.load_dict(highlight_dict(scene, description, window), optimize=False)
        part = np.asarray(mi.render(pinhole, seed=seed), np.float32)[..., 0:3]
        if subsurface and any(has_film(m) for m in scene.materials):  # the films' sheen, in the same frame
            sheen = mi.load_dict(highlight_dict(scene, description, window, film=True), optimize=False)
            part = part + np.asarray(mi.render(sheen, seed=seed, spp=FILM_SPP), np.float32)[..., 0:3]
        distance = np.zeros_like(part[..., :1])
        if description["sensor"]["type"] == "thinlens":  # its blur (``defocus``) needs each pixel's depth
            depth = mi.load_dict({"type": "aov", "aovs": DEPTH_AOV})
            distance = np.asarray(mi.render(pinhole, integrator=depth, seed=seed, spp=1), np.float32)
        part = np.concatenate([part, distance], axis=-1)
    frame = crop or Crop(0, 0, width, height)
    glints = part
    if window is not None:  # the rest of the film is the black backdrop
        glints = np.zeros(image.shape[:2] + part.shape[2:], np.float32)
        top, left = window.y - frame.y, window.x - frame.x
        glints[top : top + window.height, left : left + window.width] = part
    sharp = np.maximum(np.nan_to_num(glints[..., 0:3], nan=0.0, posinf=0.0), 0.0)
    glints = defocus(sharp, glints[..., 3], description["sensor"], width, height, frame)
    color, glints = (np.nan_to_num(x[..., 0:3], nan=0.0, posinf=0.0) * np.float32(EXPOSURE) for x in (image, glints))
    albedo, normal = np.clip(aov[..., 0:3], 0.0, 1.0), np.clip(aov[..., 3:6], -1.0, 1.0)
    return Layers(np.maximum(color, 0.0), albedo, normal, np.maximum(glints, 0.0))


def load_renderer() -> None:
    """Load every Mitsuba plugin (≈ 0.2 s for 100) and Open Image Denoise's CPU device now, so a preview that then
    renders while another thread computes never loads a shared library: a ``dlopen`` here while the other thread is
    in one can deadlock (the loader's lock against the GIL; USD's initialiser drops and retakes the GIL); numba's
    libraries and the glints' blur kernel (``bokeh``) as well. The preview node's ``overlap``
    (``nodegraph.executor.Beside``)."""
    import os

    import mitsuba as mi
    import pyoidn

    mi.set_variant(VARIANT)
    plugins = mi.PluginManager.instance()
    for name in sorted(os.listdir(Path(mi.__file__).parent / "plugins")):
        stem, suffix = os.path.splitext(name)
        if suffix in (".so", ".dylib", ".dll"):
            plugins.plugin_type(stem)  # loads the plugin's library
    blank = np.zeros((8, 8, 3), np.float32)
    pyoidn.denoise(blank, albedo=blank, normal=blank, hdr=True, quality=DENOISE_QUALITY)
    from .bokeh import scatter_discs  # numba and the glints' blur kernel (from its cache), loaded here too

    plane = np.zeros((8, 8), np.float32)  # C-contiguous, as ``defocus`` passes them: the same compiled signature
    scatter_discs(blank, plane, plane)


def denoise(layers: Layers) -> np.ndarray:
    """Intel Open Image Denoise (``pyoidn``, the RT filter, HDR) guided by albedo and normals."""
    try:
        import pyoidn
    except ImportError as error:  # a dependency of the package; say what to install if it is missing
        raise ImportError("denoising previews needs Intel Open Image Denoise: pip install pyoidn") from error
    out = pyoidn.denoise(
        np.ascontiguousarray(layers.color),
        albedo=np.ascontiguousarray(layers.albedo),
        normal=np.ascontiguousarray(layers.normal),
        hdr=True,
        clean_aux=CLEAN_AUX,
        quality=DENOISE_QUALITY,
    )
    return np.maximum(np.asarray(out, np.float32), 0.0)


def tone_map(color: np.ndarray) -> np.ndarray:
    """Linear below ``KNEE``, then an exponential shoulder towards 1 (C¹ at the knee): highlights on white rice
    and wet eggs keep a gradient instead of clipping. Input and output are linear RGB."""
    x = np.maximum(np.asarray(color, np.float32), 0.0)
    span = 1.0 - KNEE
    shoulder = KNEE + span * (1.0 - np.exp(-(x - KNEE) / span))
    return np.where(x <= KNEE, x, shoulder).astype(np.float32)


def render(
    scene: ShadedScene,
    camera: Camera,
    width: int,
    height: int,
    spp: int,
    light_direction,
    denoised: bool = True,
    seed: int = 0,
    subsurface: bool = False,
    max_depth: int | None = None,
    ambient: float = studio.AMBIENT,
    setting: str = "sweep",
) -> np.ndarray:
    """Path-traced (and denoised) preview, 8-bit sRGB (height, width, 3); ``max_depth``, ``ambient`` and
    ``setting`` as ``scene_dict``."""
    from .mesh_files import linear_to_srgb8

    layers = render_layers(
        scene,
        camera,
        width,
        height,
        spp,
        light_direction,
        seed,
        max_depth=max_depth,
        subsurface=subsurface,
        ambient=ambient,
        setting=setting,
    )
    return linear_to_srgb8(tone_map(layers.denoised() if denoised else layers.noisy()))
