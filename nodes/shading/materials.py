"""Principled material presets per element kind — G Table 3 colour columns, SPEC §4.

Colours are linear RGB in [0, 1]; lengths (subsurface radius) in mm. Cooked rice is interpolated by water content
(0–24 %, SPEC §4): wetter grains are whiter, more translucent and glossier (a water film: clearcoat). Ikura has two
parts (``Mesh.parts``: 0 membrane, 1 yolk); kakigori ice is a white tuft of fine shavings, a scattering medium with
no skin, and carries syrup graded by its depth below the mound's top surface, deeper along runs down the flanks;
chestnut (kuri gohan) is a golden, dense, waxy solid under a moist film; a fish topping (salmon, tuna) has two
parts: 0 flesh, 1 fat.
"""

from __future__ import annotations

import numpy as np

from ..values import Material
from .cdrf import WATER_MAX

PRESETS = ("rice", "ikura", "ice", "chestnut", "salmon", "tuna")
_KIND_WORDS = {
    "rice": ("rice", "japonica", "indica", "aromatic", "grain"),
    "ikura": ("ikura", "roe", "egg"),
    "ice": ("ice", "kakigori", "flake"),
    "chestnut": ("chestnut", "kuri"),
    "salmon": ("salmon", "sake"),
    "tuna": ("tuna", "maguro"),
}
ICE = "ice"  # the plain ice material's name; its syrup grades are named ice_syrup_<percent>
PARTS = {"ikura": ("membrane", "yolk"), "salmon": ("flesh", "fat"), "tuna": ("flesh", "fat")}  # Mesh.parts ids


def preset_for_kind(kind: str, overrides: dict[str, str]) -> str:
    """The preset of an element kind: an explicit ``kind=preset`` override, else by the kind's name."""
    if kind in overrides:
        return overrides[kind]
    for preset, words in _KIND_WORDS.items():
        if any(word in kind.lower() for word in words):
            return preset
    raise ValueError(
        f"element kind '{kind}' matches no material preset; name it in parameter 'presets' "
        f"as '{kind}=<preset>' with <preset> one of {', '.join(PRESETS)}"
    )


def parse_overrides(entries: list[str]) -> dict[str, str]:
    """``["japonica=rice", ...]`` → dict, refusing unknown presets and malformed entries."""
    out = {}
    for entry in entries:
        kind, sep, preset = entry.partition("=")
        if not sep or not kind or preset not in PRESETS:
            raise ValueError(f"presets entry '{entry}': expected 'kind=preset' with preset one of {', '.join(PRESETS)}")
        out[kind] = preset
    return out


def _mix(dry, wet, t):
    return tuple(float(a + (b - a) * t) for a, b in zip(dry, wet))


def _absorb(clear, dyed, t):
    """Colour at a share ``t`` of dye: the absorption (−ln of the colour) grows linearly with the concentration
    (Beer–Lambert), so the colour mixes geometrically; a linear mix would leave half-soaked ice pale pink."""
    return tuple(float(a ** (1.0 - t) * max(b, 1e-6) ** t) for a, b in zip(clear, dyed))


# the subsurface radius (mm) of rice at the wettest (24 %): its medium's mean free path in red is then 1.65 mm at 24 %
# and 1.15 mm at 15 % (one σt for every channel: 0.85 and 1.14 mm⁻¹), the wet end at the starchy stand-in's, potato
# (Jensen et al. 2001, table 2: 1/σ′s = 1.47, 1.43, 1.82 mm); at (1.2, 0.9, 0.6) grains read as opaque pebbles.
# Bounded by the grain's optical thickness (σt × 2.0 mm ≥ 2 up to 18 % water,
# tests/scenes/test_grain_optics.py: thinner, light crosses a grain unscattered and rice reads as glass; docs/look.md,
# "Cooked rice: wet, milky, warm")
RICE_RADIUS_WET = (1.6, 1.2, 0.8)
# the roughness of the grain's skin, its water-and-starch film, dry → wet (0.225 at 15 %: α 0.05). A cooked grain's
# adherent starch layer is smooth (Cookery Science 42(6):394), and graders judge cooked rice by its gloss (tsuya, by
# eye: Japan Grain Inspection Association; by image analysis, the share of high-luminance pixels: Hokkaido Central
# Agricultural Experiment Station 1999). At 0.156 at 15 % (α 0.024) the skin mirrored the key in every grain and
# art directors read "pills"; at 0.325 (α 0.11) the sheen spread over each grain and they read dry, chalky rice
# with "no sheen". No published BRDF of cooked rice was found: the pair is chosen (docs/look.md, "A bowl of rice")
RICE_FILM_ROUGHNESS = (0.40, 0.12)
# the subsurface colour of the wettest rice (24 %), the dry end's (0.80, 0.65, 0.44) being raw rice's cream; at 15 %
# (0.87, 0.79, 0.67). At (0.91, 0.81, 0.665) at 15 % the heap was cream and lit grains sat at the tone curve's
# knee, leaving the film's sheen no headroom (art directors: "chalky, no sheen"); chosen, no measured values
# (docs/look.md, "Warm white rice")
RICE_COLOR_WET = (0.91, 0.875, 0.81)


def rice_material(water: float, name: str = "rice") -> Material:
    """Cooked (or raw) rice at a water content in % — translucency, whiteness, gloss grow with water.

    ``subsurface`` scales the CDRF's diffuse transmission (``cdrf.translucency``, per vertex from σ₀|κ|);
    the water film adds a clearcoat and a sheen at grazing angles (G fig. 3.1.2.1: dull at 0 %, glossy at 24 %).
    The subsurface colour is a warm white, chosen (no measured values): thin grains let most light through, so a
    heap shows their colour weaker than a thick piece would; at (0.90, 0.86, 0.76) (15 %) the studio rendered the
    rice neutral grey (CIELAB b* 3.8), at (0.91, 0.81, 0.665) cream and chalky (``RICE_COLOR_WET``). The wet
    end's blue, 0.81, keeps its single-scattering albedo at 0.99: wetter is whiter in every channel.
    """
    if not 0.0 <= water <= WATER_MAX:
        raise ValueError(f"water_content {water} % is outside 0–{WATER_MAX:g} %")
    t = water / WATER_MAX
    return Material(
        name=name,
        base_color=_mix((0.66, 0.60, 0.47), (0.90, 0.89, 0.84), t),
        subsurface=0.3 + 0.6 * t,
        subsurface_radius=_mix((0.3, 0.2, 0.1), RICE_RADIUS_WET, t),
        subsurface_color=_mix((0.80, 0.65, 0.44), RICE_COLOR_WET, t),
        specular=0.5,
        roughness=0.7 - 0.35 * t,
        sheen=0.6 * t,
        sheen_tint=0.3,
        clearcoat=0.5 * t,
        clearcoat_roughness=_mix((RICE_FILM_ROUGHNESS[0],), (RICE_FILM_ROUGHNESS[1],), t)[0],
        ior=1.45 - 0.08 * t,
    )


EGG_TINTS = 12  # membrane tints the eggs of a scene are drawn from (the shade node's ``egg_tints``)
# the spread of the eggs' colour (``ikura_tints``): salmon roe is graded "light orange, orange, reddish-orange, red ...
# shiny, slightly transparent" (caviar quality assessment checklist, table 6-1, markys.com/beluga/tab6-1.htm): the green
# absorbance of the fluid scaled over EGG_HUE_SPREAD moves the hue of light through an egg from CIELAB h 67° (orange)
# to 40° (red-orange); its pigment (astaxanthin) concentration over EGG_PIGMENT_SPREAD makes an egg lighter and
# more translucent or deeper: L* 51–70 (docs/look.md, "Ikura colour")
EGG_HUE_SPREAD = (0.55, 1.45)
EGG_PIGMENT_SPREAD = (0.70, 1.40)
EGG_FLUID = (0.85, 0.10, 0.012)  # light through the whole egg (two crossings of the fluid): the palette's centre
# the chorion is a smooth, wet membrane under tension: a near-mirror skin with a sharp highlight of the key
# (at 0.2 the eggs read frosted, the highlight a smear and the droplet behind it blurred; art directors: "identical
# beads"). 0.05 (α 0.0025) rather than 0: the surface is not optically flat over a pixel's footprint
MEMBRANE_ROUGHNESS = 0.05
# the oil droplet is "numerous little drop-like fat inclusions containing lipochromes" (1-800-caviar.com): an
# emulsion, so it scatters (as milk does) and is pale, the honey-coloured centre graders look for (ASMI). Its
# multiple-scattering colour is a pale honey-gold, linear (0.98, 0.70, 0.28) = sRGB (254, 218, 145): chosen, no
# measured spectrum of roe oil at hand. As an orange (1.0, 0.50, 0.10) ball of mean free path up to 1 mm it scattered
# light back in the fluid's own hue, and the eye did not read against the red (docs/look.md, "The pale eye"). Its
# free path (0.5, 0.4, 0.3) mm, a few across the 4 mm droplet: a cloudy drop, seen through the thin fluid over it
DROPLET_COLOR = (0.98, 0.70, 0.28)
DROPLET_RADIUS = (0.5, 0.4, 0.3)
DROPLET_ROUGHNESS = 0.05  # an oil–water interface, smooth under its tension as the membrane is


def ikura_materials() -> tuple[Material, Material]:
    """(membrane, yolk): a clear dielectric skin (IOR 1.36) holding a deep orange-red fluid, around an oil yolk.

    Both are transmissive: the membrane's ``subsurface_color`` is the colour light keeps after crossing the egg;
    the yolk (oil, IOR 1.47, in the egg fluid) is a scattering medium of that colour behind a smooth skin
    (``DROPLET_COLOR``), so it shows through the membrane as a paler, cloudy honey-gold core. No diffuse surface
    inside an egg is lit only through its skin, which keeps the preview's caustic noise low.

    Colour: the roe's pigment is astaxanthin, absorbing blue and green (maximum ≈ 470–480 nm) and passing red, so
    light through an egg keeps its red, a little of its green and almost no blue. No measured spectrum of ikura is
    at hand: the fluid's colour is chosen to read as ikura's deep orange-red, linear (0.80, 0.07, 0.01) = sRGB
    (231, 75, 25), CIELAB hue 45° and chroma 83 (it was (0.90, 0.20, 0.02) = sRGB (243, 124, 39), hue 57° and
    chroma 75: amber), and light through the whole egg (two crossings of the fluid) keeps ``EGG_FLUID``
    (0.85, 0.10, 0.012); the yolk's oil is pale honey-gold, the colour of honey at the egg's centre that graders
    look for (Alaska Seafood Marketing Institute: "a center the color and consistency of honey"). Each egg of a scene
    takes one of ``ikura_tints`` of this membrane.
    """
    membrane = Material(
        name="ikura_membrane",
        base_color=(0.80, 0.07, 0.01),
        subsurface=0.0,
        subsurface_radius=(4.0, 1.2, 0.5),
        subsurface_color=EGG_FLUID,
        specular=0.5,
        roughness=MEMBRANE_ROUGHNESS,
        clearcoat=1.0,
        clearcoat_roughness=0.02,
        ior=1.36,
        transmission=1.0,
        transmission_roughness=MEMBRANE_ROUGHNESS,
    )
    yolk = Material(
        name="ikura_yolk",
        base_color=DROPLET_COLOR,
        subsurface=0.0,
        subsurface_radius=DROPLET_RADIUS,
        subsurface_color=DROPLET_COLOR,
        roughness=DROPLET_ROUGHNESS,
        ior=1.47,
        exterior_ior=1.36,
        transmission=1.0,
        transmission_roughness=DROPLET_ROUGHNESS,
    )
    return membrane, yolk


def _absorbed(color, hue: float, pigment: float) -> tuple[float, float, float]:
    """``color`` (a transmittance) with its absorbance scaled by ``pigment`` in every channel and by ``hue`` more
    in green (Beer–Lambert: more astaxanthin absorbs more; less green absorbed is more orange)."""
    absorbance = -np.log(np.clip(np.asarray(color, np.float64), 1e-6, 1.0)) * pigment * np.array([1.0, hue, 1.0])
    return tuple(float(c) for c in np.exp(-absorbance))


def ikura_tints(count: int) -> tuple[Material, ...]:
    """``count`` membranes (``ikura_materials``' first) from orange to red-orange, lighter to deeper: tint k has
    the green absorbance ``EGG_HUE_SPREAD`` at (k + ½)/count and the pigment ``EGG_PIGMENT_SPREAD`` at the golden
    ratio's k-th step (a low-discrepancy pair: every hue with its own depth). Named ``ikura_membrane_<k>``; one
    tint is the membrane itself, named ``ikura_membrane``."""
    import dataclasses

    membrane = ikura_materials()[0]
    if count == 1:
        return (membrane,)
    golden = (np.sqrt(5.0) - 1.0) / 2.0
    tints = []
    for k in range(count):
        hue = float(np.interp((k + 0.5) / count, [0.0, 1.0], EGG_HUE_SPREAD))
        pigment = float(np.interp((0.5 + k * golden) % 1.0, [0.0, 1.0], EGG_PIGMENT_SPREAD))
        tints.append(
            dataclasses.replace(
                membrane,
                name=f"ikura_membrane_{k:02d}",
                base_color=_absorbed(membrane.base_color, hue, pigment),
                subsurface_color=_absorbed(membrane.subsurface_color, hue, pigment),
            )
        )
    return tuple(tints)


def ice_materials(syrup_color) -> tuple[Material, Material]:
    """(plain shaved ice, syrup-soaked shaved ice). A flake stands for a tuft of shavings far finer than the mesh (a
    kakigori machine planes ice 0.05–0.1 mm thin): ice with air between, white from its countless interfaces as snow
    is, not a clear crystal. The preview renders it as what it is, light scattered under the surface: a dense,
    nearly lossless medium (free path ``subsurface_radius`` 0.2 mm, multiple-scattering albedo ``subsurface_color``
    0.96–0.97; ice absorbs nothing over millimetres) behind no skin (``mitsuba_scene.boundary_bsdf``: the tuft's
    pores open to the air). Light walks through a flake and on to the flakes behind, and comes back out of the heap
    white; behind a dielectric skin the part that crossed a flake unscattered was refracted as by glass, and the
    heap read as grey glass (docs/look.md, "Kakigori"). Where a renderer has no medium (the preview with
    ``subsurface`` off, a glTF viewer), the same flake is a matte thin diffuser: near-Lambertian, high albedo
    (``base_color``), no glassy facet (roughness 1, the tuft's effective index ≈ 1.1 for ≈ 30 % ice in air), passing
    ``subsurface`` of its diffuse light on, on every part of the flake alike (no CDRF per vertex). Syrup fills the
    pores: its dye absorbs green and blue and passes red, so the soaked tuft's medium keeps red at the ice's albedo
    and takes the green and blue at the square of the syrup's hue (``syrup_color`` over its red: twice the dye's
    absorbance), so that the soaked top renders the syrup's own colour (at the hue itself the default syrup's top
    rendered sRGB (226, 86, 114), pink, against the syrup's (225, 39, 69); squared (224, 50, 74); docs/look.md,
    "Kakigori"). Its free path is short (0.05 mm) because absorption happens at the medium's collisions (one σt for
    every channel, ``mitsuba_scene.medium``): a strong dye needs many of them in a 0.3 mm flake (at 0.6 mm the top
    rendered pale pink; at 0.25 mm pink, with a skin over it). Soaked through (``is_wet``), the tuft is one
    liquid-filled body behind a smooth skin at the syrup's index. It is wet: glossy (roughness 0.15, index 1.33)
    under a clear coat (the key's glints; ``mitsuba_scene.gloss``), and as a thin diffuser passes 90 % of its
    diffuse light on, 30 % straight through (index-matched ice and syrup are clear)."""
    ice = Material(
        name=ICE,
        base_color=(0.96, 0.965, 0.97),
        subsurface=0.25,
        subsurface_radius=(0.2, 0.2, 0.2),
        subsurface_color=(0.96, 0.965, 0.97),
        roughness=1.0,
        specular=0.2,
        ior=1.1,
    )
    hue = np.asarray(syrup_color, np.float64) / max(float(np.max(syrup_color)), 1e-6)
    soaked = tuple(float(c) for c in np.asarray(ice.base_color) * hue**2)
    syrup = Material(
        name="ice_syrup",
        base_color=soaked,
        subsurface=0.9,
        subsurface_radius=(0.05, 0.05, 0.05),
        subsurface_color=soaked,
        roughness=0.15,
        clearcoat=0.7,
        clearcoat_roughness=0.08,
        ior=1.33,
        transmission=0.3,
        transmission_roughness=0.2,
    )
    return ice, syrup


def is_ice(material: Material) -> bool:
    """Whether a material is kakigori ice (plain or a syrup grade): a scattering medium in the preview, with no
    skin unless soaked through (``is_wet``; ``mitsuba_scene.boundary_bsdf``), else a thin diffuser whose diffuse
    transmission is its ``subsurface`` on every vertex (no CDRF); the preview traces longer paths through a heap of
    them (``mitsuba_scene.path_depth``)."""
    return material.name == ICE or material.name.startswith(ICE + "_syrup")


# the share of syrup in a tuft's pores from which it is wet through: the liquid joins up between the shavings and
# its one surface (a dielectric skin at the liquid's index, as smooth as its film: ``look.has_skin``) gives the
# soaked top its wet gloss; a tuft with less is damp shavings, their pores still open to the air
WET_SHARE = 0.5


def is_wet(material: Material) -> bool:
    """Whether a material is shaved ice soaked through with syrup (a grade ``ice_syrup_<percent>`` of at least
    ``WET_SHARE``)."""
    prefix = ICE + "_syrup_"
    return material.name.startswith(prefix) and int(material.name.removeprefix(prefix)) >= 100 * WET_SHARE


def syrup_grades(ice: Material, syrup: Material, levels: int) -> tuple[Material, ...]:
    """``levels`` + 1 materials from plain ice (0) to fully soaked (``levels``): share k/levels of the syrup in the
    flake's pores. Its colour is absorbed (``_absorb``: geometric mix); free path, index, gloss and coat mix
    linearly."""
    if levels < 1:
        raise ValueError(f"syrup levels must be ≥ 1, got {levels}")
    graded = [ice]
    for k in range(1, levels + 1):
        t = k / levels
        graded.append(
            Material(
                name=f"ice_syrup_{round(100 * t):d}",
                base_color=_absorb(ice.base_color, syrup.base_color, t),
                subsurface=ice.subsurface + (syrup.subsurface - ice.subsurface) * t,
                subsurface_radius=_mix(ice.subsurface_radius, syrup.subsurface_radius, t),
                subsurface_color=_absorb(ice.subsurface_color, syrup.subsurface_color, t),
                roughness=ice.roughness + (syrup.roughness - ice.roughness) * t,
                clearcoat=syrup.clearcoat * t,
                clearcoat_roughness=syrup.clearcoat_roughness,
                ior=ice.ior + (syrup.ior - ice.ior) * t,
                transmission=ice.transmission + (syrup.transmission - ice.transmission) * t,
                transmission_roughness=ice.transmission_roughness
                + (syrup.transmission_roughness - ice.transmission_roughness) * t,
            )
        )
    return tuple(graded)


def chestnut_material() -> Material:
    """Chestnut (kuri, as in kuri gohan): a peeled kernel cooked in the rice, dyed golden yellow with gardenia
    (kuchinashi, whose yellow colours kuri kinton: murin-an.jp/news/staff-viewpoint/eyes-20191221); a dense, waxy
    body (subsurface 0.3 over a short radius: light softens its edges and does not cross it, as it crosses rice)
    under a moist film of starch and cooking water (clear coat 0.7 at roughness 0.35, softer than the rice's: a
    soft glint on each cut face). Colour linear (0.80, 0.52, 0.15) = sRGB (231, 191, 108): the dyed colour
    kuchinashi-iro, Munsell 4Y 8/8 = sRGB (231, 195, 87) (natubunko.net/mmbn/fushin042.html), taken a little
    paler, as a kernel dyed through its cooking water is (chosen). In a pale cream (sRGB (228, 201, 148)), matte
    (roughness 0.65), art directors read the pieces as "pale mustard blobs, cheese cubes" (issue 48)."""
    return Material(
        name="chestnut",
        base_color=(0.80, 0.52, 0.15),
        subsurface=0.3,
        subsurface_radius=(0.8, 0.5, 0.2),
        subsurface_color=(0.90, 0.62, 0.22),
        specular=0.4,
        roughness=0.5,
        sheen=0.2,
        sheen_tint=0.5,
        clearcoat=0.7,
        clearcoat_roughness=0.35,
        ior=1.45,
    )


# a raw slice is wet and smooth: its skin is a water film (roughness 0.08, α 0.0064), the key's sharp glint on it,
# broken into one glint a flake by the flakes' relief (``plate_drape.flake_relief``)
FISH_FILM_ROUGHNESS = 0.08


def fish_materials(kind: str) -> tuple[Material, Material]:
    """(flesh, fat) of a raw fish topping. The flesh is light under a wet skin: the preview fills the slab with a
    scattering medium (``look.VOLUMETRIC_ELEMENTS``) behind a smooth dielectric film (``FISH_FILM_ROUGHNESS``), so
    light enters it, glows through its thin edges and comes back coloured, and the film gives the wet sheen. Red
    light travels furthest (subsurface radius 3 mm in red; Johansen 2008, NTNU: optical penetration depth in
    Atlantic salmon 6.79 ± 0.33 mm at 632.8 nm); green and blue are absorbed by the pigment (astaxanthin in salmon,
    myoglobin in tuna) within a millimetre. The fat lines (the myosepta's fat and collagen) are a dense white
    scatterer seen as an opaque cream surface under the same wet coat: light in the flesh that reaches one is sent
    back into the flesh. As a medium of their own, light entering a 0.7 mm line walked off through the flesh and
    the lines rendered grey. Salmon's fat is a pale pink cream (chosen): in a whiter cream (0.86, 0.72, 0.58) the
    lines read as painted stripes. ``kind``: salmon (orange flesh, marked fat) or tuna (akami: deep red
    flesh, faint fat)."""
    if kind == "salmon":
        flesh_color, flesh_sss, fat_color = (0.90, 0.22, 0.07), (0.99, 0.30, 0.10), (0.80, 0.56, 0.44)
    elif kind == "tuna":
        flesh_color, flesh_sss, fat_color = (0.42, 0.03, 0.04), (0.70, 0.08, 0.08), (0.80, 0.50, 0.48)
    else:
        raise ValueError(f"fish kind '{kind}': expected salmon or tuna")
    flesh = Material(
        name=f"{kind}_flesh",
        base_color=flesh_color,
        subsurface=1.0,
        subsurface_radius=(3.0, 1.0, 0.5),
        subsurface_color=flesh_sss,
        roughness=0.3,
        clearcoat=1.0,
        clearcoat_roughness=FISH_FILM_ROUGHNESS,
        ior=1.38,
    )
    fat = Material(
        name=f"{kind}_fat",
        base_color=fat_color,
        roughness=0.5,
        clearcoat=1.0,
        clearcoat_roughness=FISH_FILM_ROUGHNESS,
        ior=1.38,
    )
    return flesh, fat


NORI = "nori"  # a scenery mesh of this name (the ``nori`` node's band) gets ``nori_material``


def nori_material() -> Material:
    """Nori (dried, toasted laver sheet): black-green and dry. Base linear (0.010, 0.026, 0.012) = sRGB (25, 45, 29),
    L* 16 as a diffuse albedo (at sRGB (31, 42, 30), the same L* less green, the band rendered grey); the one
    published figure at hand, L* 29.1, a* 1.6, b* 2.1 for a test sheet of Vietnamese Porphyra (Tạp chí Công
    Thương, "nori from Porphyra harvested in Khánh Hòa"), is a colorimeter's, specular included (a black surface's
    4 % alone reads L* 24), so the albedo under it is darker; commercial yaki-nori is greener. A dry, fibrous face:
    one broad specular lobe (roughness 0.55, F0 0.04), no clear coat and a faint sheen in its own colour; the
    sheet's crinkles and fibres (the ``nori`` node's ``crinkle``) give it its texture. With a satin face (roughness
    0.42, a clear coat, a white-ish sheen 0.6) it reflected the studio and read as grey rubber."""
    return Material(
        name=NORI,
        base_color=(0.010, 0.026, 0.012),
        roughness=0.55,
        sheen=0.25,
        sheen_tint=0.9,
        clearcoat=0.0,
        clearcoat_roughness=0.3,
        ior=1.5,
    )


CERAMIC = "ceramic"


def ceramic_material(color, roughness: float = 0.04) -> Material:
    """The bowl (scenery): a glazed ceramic — a coloured body under a glaze. A glaze is a glass, a dielectric
    (metallic 0): the one surface that reflects is the glaze's top (the clear coat, F0 0.04 at IOR 1.5; roughness
    0.04 glossy, ≈ 0.3 a satin glaze: ``shade.scenery_roughness``); the colour lies in and under the glass, seen
    only diffusely (roughness 1, no specular of its own: the glass over the body is index-matched). With a specular
    lobe of its own at roughness 0.35 the dark glaze reflected the studio as a broad grey sheen, and the bowl read
    grey, its rim as brushed metal (docs/look.md, "The bowl's glaze")."""
    return coated(CERAMIC, tuple(float(c) for c in color), roughness)


def coated(name: str, color, coat_roughness: float) -> Material:
    """A colour seen only diffusely under one smooth dielectric coat (F0 0.04 at IOR 1.5): a glaze or a lacquer,
    with no specular lobe of its own."""
    return Material(
        name=name,
        base_color=color,
        specular=0.0,
        roughness=1.0,
        clearcoat=1.0,
        clearcoat_roughness=coat_roughness,
        ior=1.5,
    )


LACQUER = "lacquer"  # a scenery mesh named ``chopsticks.NAME`` gets ``lacquer_material``
PROPS = (LACQUER,)  # materials of props: on the table beside the dish, not part of what the camera frames


def lacquer_material() -> Material:
    """Lacquered chopsticks (urushi over wood): like a glaze, a dielectric (metallic 0) whose one reflecting
    surface is the lacquer's smooth top (the clear coat, F0 0.04, roughness 0.08: polished, not a mirror), the
    colour seen diffusely under it (no specular of its own). Black lacquer (kuro-urushi), linear (0.025, 0.020,
    0.018) = sRGB (44, 39, 37): chosen, not measured (lacquer runs from black through tame-nuri brown to vermilion);
    a deep red-brown (sRGB (89, 44, 28)) read on the oak as a groove between its boards, black with the key's
    glint along it reads as a glossy stick."""
    return coated(LACQUER, (0.025, 0.020, 0.018), 0.08)


def soak_depths(vertices: list[np.ndarray], cell: float, spread: float) -> np.ndarray:
    """Each element's depth below the aggregate's top surface as the syrup sees it (mm). The top is the upper
    envelope of all element vertices over a horizontal grid of ``cell`` mm (the highest vertex per column),
    widened by a maximum over a disc of radius ``spread`` (syrup poured on top runs that far sideways as it
    soaks down, so a flank lies below the summit beside it, not on a surface of its own); an element's depth
    is that top over its highest vertex minus the vertex's height (0: on top)."""
    from scipy.ndimage import maximum_filter

    if not vertices:
        return np.zeros(0)
    tops = np.array([v[np.argmax(v[:, 2])] for v in vertices])
    points = np.concatenate(vertices)
    lo = points[:, :2].min(axis=0)
    cells = np.floor((points[:, :2] - lo) / cell).astype(np.int64)
    shape = cells.max(axis=0) + 1
    envelope = np.full((int(shape[0]), int(shape[1])), -np.inf)
    np.maximum.at(envelope, (cells[:, 0], cells[:, 1]), points[:, 2])
    reach = int(np.floor(spread / cell))
    if reach > 0:
        i, j = np.mgrid[-reach : reach + 1, -reach : reach + 1]
        envelope = maximum_filter(envelope, footprint=i**2 + j**2 <= reach**2, mode="constant", cval=-np.inf)
    own = np.floor((tops[:, :2] - lo) / cell).astype(np.int64)
    return np.maximum(envelope[own[:, 0], own[:, 1]] - tops[:, 2], 0.0)


def syrup_runs(tops: np.ndarray, soak_depth: float, runs: int, length: float, width: float, rng) -> np.ndarray:
    """How deep the syrup soaks at each element (mm): ``soak_depth``, and where one of ``runs`` streaks runs down
    the flank, up to ``length`` more. Syrup poured on a mound does not sink as an even band: it runs down in
    streaks and drips. A run has a random azimuth about the mound's axis (the elements' mean x, y; one run in each
    of ``runs`` equal sectors, so every side of the mound has its share whatever the seed), a length up to
    ``length`` (0.4–1 of it) and a width along the flank of 0.5–1.5 ``width``; its extra depth falls off with
    the arc from its centre line (Gaussian), so it tapers to a rounded tip. ``tops``: each element's highest
    vertex; ``rng`` draws the runs (the recipe's seed)."""
    limit = np.full(len(tops), float(soak_depth))
    if runs <= 0 or length <= 0 or not len(tops):
        return limit
    azimuth = 2.0 * np.pi * (np.arange(runs) + rng.uniform(0.0, 1.0, runs)) / runs  # one in each sector: all round
    extra = length * rng.uniform(0.4, 1.0, runs)
    half = width * rng.uniform(0.5, 1.5, runs)
    rel = tops[:, :2] - tops[:, :2].mean(axis=0)
    theta = np.arctan2(rel[:, 1], rel[:, 0])
    turn = np.angle(np.exp(1j * (theta[:, None] - azimuth[None, :])))  # wrapped to (−π, π]
    arc = np.hypot(rel[:, 0], rel[:, 1])[:, None] * np.abs(turn)
    return limit + (extra * np.exp(-((arc / half) ** 2))).max(axis=1)


def syrup_levels(depths: np.ndarray, soak_depth, levels: int) -> np.ndarray:
    """Syrup grade per element, 0 (plain ice) … ``levels`` (soaked): the concentration falls linearly from 1 at
    the top surface to 0 at ``soak_depth`` below it (one depth, or one per element: ``syrup_runs``; syrup poured on
    top, drawn down by gravity through the flakes), rounded to the nearest of ``levels`` steps."""
    limit = np.broadcast_to(np.asarray(soak_depth, np.float64), np.shape(depths))
    concentration = np.zeros(np.shape(depths))
    wet = limit > 0
    concentration[wet] = np.clip(1.0 - np.asarray(depths)[wet] / limit[wet], 0.0, 1.0)
    return np.rint(concentration * levels).astype(np.int64)
