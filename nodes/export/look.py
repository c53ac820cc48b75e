"""The whole principled look of a material as flat name → value pairs, carried by both exported files.

UsdPreviewSurface and glTF's extensions each say part of what the preview renders; these attributes say all of
it, under one name each, so that one reader (the Blender add-on in ``blender/nodegraph_import``) sets the same
Principled BSDF from either file: on the USD Material prim as ``nodegraph:principled:<name>``, in the glTF
material's ``extras`` under the same key. Colours are tuples of linear RGB; the subsurface radius is in mm, the
unit of the meshes.

A transmissive element's skin tints the light at each crossing (``crossing_tint``), as the preview renders it; both
files carry the colour of two crossings (``subsurface_color``) as the base colour, of which Blender's principled BSDF
applies the square root at each crossing, and no volume absorption on top. An element the preview fills with a
scattering medium (rice grains, ikura yolks, shaved ice) carries the medium's coefficients (``medium*``; ``boundaryIor``
1 where the medium has no skin: ice), so that a renderer that can build a medium (Cycles, through the add-on) renders
the same light under the skin.
"""

from __future__ import annotations

import numpy as np

from ..values import Material

PREFIX = "nodegraph:principled:"
# elements whose inside scatters (and shaved ice: ``is_ice``): closed rice grains and yolks, and the fish slab's flesh,
# which closes the slab with its fat lines: light enters through the flesh's faces, and the fat's opaque faces
# reflect it back into the flesh from inside (a ray keeps its medium on a reflection)
VOLUMETRIC_ELEMENTS = ("rice", "ikura_yolk", "salmon_flesh", "tuna_flesh")
# elements whose skin is a thin wet film over their medium: cooked rice, coated by the adherent layer of starch and
# water it took up in cooking (Cookery Science 42(6):394). The film reflects Fresnel's share at its roughness and
# passes the rest without bending it (``has_film``)
FILMED_ELEMENTS = ("rice",)
# the medium behind a film stands in for the grain behind a refracting skin (``film_medium``): σt scaled by this and
# each channel's albedo the dipole's equivalent (``film_albedo``) keep a grain-thick slab's reflectance and
# transmittance (2.7 mm, 15 % water, normal incidence) within 0.02 of the refracting skin's (random walk, 60,000
# paths; docs/look.md, "Cooked rice: a wet film over a milky grain"); unscaled, R was 0.04 under and T 0.06 under
FILM_SIGMA_T = 0.8
TRANSMISSIVE = 0.5  # transmission at or above which a material is a dielectric


def principled_attributes(material: Material, translucency: float) -> dict[str, float | tuple[float, ...]]:
    """The material's principled set; ``translucency`` is its diffuse-transmission weight (``subsurface`` times
    the CDRF's translucency at the material's median σ, ``gltf_writer.material_translucency``)."""
    look = {
        "ior": float(material.ior),
        "transmission": float(material.transmission),
        "transmissionRoughness": float(material.transmission_roughness),
        "subsurface": float(material.subsurface),
        "subsurfaceColor": tuple(float(c) for c in material.subsurface_color),
        "subsurfaceRadius": tuple(float(c) for c in material.subsurface_radius),
        "diffuseTransmission": float(translucency),
        "sheen": float(material.sheen),
        "sheenTint": float(material.sheen_tint),
        "specular": exported_specular(material),
    }
    if coat_is_skin(material):
        look["coatIor"] = float(material.ior)
    if material.exterior_ior != 1.0:  # an element inside another (the yolk in the egg's fluid)
        look["exteriorIor"] = float(material.exterior_ior)
    if is_volumetric(material):
        sigma_t, albedo = medium_coefficients(material)
        look["mediumSigmaT"] = sigma_t  # mm⁻¹, every channel
        look["mediumAlbedo"] = tuple(float(c) for c in albedo)
        look["boundaryRoughness"] = boundary_roughness(material)
        if not has_skin(material):  # index-matched: the boundary does not bend the light
            look["boundaryIor"] = 1.0
        if has_film(material):  # what reflects is the film over it, at the element's IOR
            look["filmIor"] = float(material.ior)
    return look


def coat_is_skin(material: Material) -> bool:
    """Whether ``material``'s clear coat is the only surface that reflects: a coated transmissive element with no
    medium inside (the ikura membrane). The preview renders one skin there: a dielectric at the material's IOR,
    whose sharp gloss is its clear coat (the glints' pass). A principled BSDF with both a coat (glTF: IOR 1.5) and
    its own specular reflects twice: in Blender the eggs came out pale orange under a whitish sheen. Both files
    give it no specular of its own (``exported_specular``) and the coat at the material's IOR (``coatIor``). Cycles'
    transmission lobe reflects by Fresnel at the IOR whatever its specular level, so there the add-on drops the coat
    and that lobe is the one skin (``blender/nodegraph_import``; docs/look.md, "Which renderer is wrong")."""
    return material.transmission >= TRANSMISSIVE and material.clearcoat > 0 and not is_volumetric(material)


def exported_specular(material: Material) -> float:
    """Blender's specular IOR level (0.5: Fresnel at the IOR, 0: no reflection) both files give ``material``: 0
    where its coat is its skin (``coat_is_skin``), else its own."""
    return 0.0 if coat_is_skin(material) else float(material.specular)


def crossing_tint(material: Material) -> np.ndarray:
    """Transmittance of a transmissive element's skin at each crossing, √``subsurface_color``: light in and out
    through the element keeps its subsurface colour (the ikura membrane: deep orange-red through the egg)."""
    return np.sqrt(np.clip(np.asarray(material.subsurface_color, np.float64), 0.0, 1.0))


def exported_base_color(material: Material) -> tuple[float, float, float]:
    """The base colour both files carry: a transmissive material's ``subsurface_color``, the colour light keeps
    through the whole element (in and out), else its base colour. Blender's principled BSDF tints each crossing by
    √base colour (Cycles: ``transmission_tint = sqrt(base_color)``), so two crossings keep the base colour, as
    the preview's two ``crossing_tint`` do; glTF's transmission tints the transmitted light by it once."""
    color = material.subsurface_color if material.transmission >= TRANSMISSIVE else material.base_color
    return tuple(float(c) for c in color)


def random_walk_coefficients(albedo, radius) -> tuple[np.ndarray, np.ndarray]:
    """(σt in mm⁻¹, single-scattering albedo) per channel from a principled subsurface colour (multiple-scattering
    albedo A) and radius (mean free path d, mm): Chiang, Kutz, Burley 2016, eq. for α and s, as in Cycles."""
    a = np.clip(np.asarray(albedo, np.float64), 0.0, 0.999)
    d = np.maximum(np.asarray(radius, np.float64), 1e-6)
    single = 1.0 - np.exp(a * (-5.09406 + a * (2.61188 - a * 4.31805)))
    s = 1.9 - a + 3.5 * (a - 0.8) ** 2
    return 1.0 / (d * s), single


def is_volumetric(material: Material) -> bool:
    """Whether the preview renders ``material``'s inside as a scattering medium (``VOLUMETRIC_ELEMENTS``: rice
    grains, ikura yolks, the fish slab's flesh; shaved ice and its syrup grades)."""
    from ..shading.materials import is_ice

    return material.name in VOLUMETRIC_ELEMENTS or is_ice(material)


def has_skin(material: Material) -> bool:
    """Whether a volumetric element's medium lies behind a dielectric skin that bends the light (yolks, fish flesh,
    shaved ice soaked with syrup: ``materials.is_wet``) or behind an index-matched boundary (dry shaved ice: a tuft
    of shavings whose pores open to the air; rice: its film, ``has_film``; ``mitsuba_scene.boundary_bsdf``)."""
    from ..shading.materials import is_ice, is_wet

    return (not is_ice(material) or is_wet(material)) and not has_film(material)


def has_film(material: Material) -> bool:
    """Whether a volumetric element's skin is a thin film (``FILMED_ELEMENTS``: cooked rice) that reflects Fresnel's
    share at its roughness and passes the rest unbent. Its light under the skin converges in a few samples, since
    every scattering event inside samples the lights through the film (``mitsuba_scene.medium``); behind a refracting
    skin none can, and at the preview's 3-5 spp the denoiser made chalky beads of a few bright samples (docs/look.md,
    "Cooked rice: a wet film over a milky grain")."""
    return material.name in FILMED_ELEMENTS


def medium_coefficients(material: Material) -> tuple[float, np.ndarray]:
    """(σt in mm⁻¹, the same in every channel; single-scattering albedo per channel) of the medium inside a
    volumetric element (``medium``): what the exported files hand a renderer that builds the same medium; behind a
    film (``has_film``), the medium that stands in for the grain behind a refracting skin (``film_medium``)."""
    sigma_t, single = random_walk_coefficients(material.subsurface_color, material.subsurface_radius)
    if has_film(material):
        return film_medium(float(sigma_t.mean()), single, material.ior)
    return float(sigma_t.mean()), single


def diffuse_reflectance(albedo, n: float) -> np.ndarray:
    """Total diffuse reflectance of a semi-infinite isotropic medium of single-scattering ``albedo`` behind index
    ``n`` (the dipole: Jensen, Marschner, Levoy and Hanrahan 2001, with Groenhuis et al.'s F_dr)."""
    a = np.asarray(albedo, np.float64)
    fdr = -1.440 / n**2 + 0.710 / n + 0.668 + 0.0636 * n
    big_a = (1.0 + fdr) / (1.0 - fdr)
    s = np.sqrt(3.0 * (1.0 - a))
    return a / 2.0 * (1.0 + np.exp(-4.0 / 3.0 * big_a * s)) * np.exp(-s)


def film_albedo(albedo, n: float) -> np.ndarray:
    """The single-scattering albedo whose medium behind no boundary reflects as much light as one of ``albedo``
    behind index ``n`` (``diffuse_reflectance``; bisection): a refracting skin keeps light inside by total internal
    reflection, where more of it is absorbed, so the index-matched equivalent absorbs more."""
    target = diffuse_reflectance(albedo, n)
    lo, hi = np.zeros_like(target), np.ones_like(target)
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        below = diffuse_reflectance(mid, 1.0) < target
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def film_medium(sigma_t: float, albedo, n: float) -> tuple[float, np.ndarray]:
    """(σt, albedo) behind a film for a medium of ``sigma_t`` and ``albedo`` behind a refracting skin of index
    ``n``: σt × ``FILM_SIGMA_T``, the albedo ``film_albedo``'s."""
    return sigma_t * FILM_SIGMA_T, film_albedo(albedo, n)


def boundary_roughness(material: Material) -> float:
    """The principled roughness of a volumetric element's skin: the files' (Cycles' multiscatter GGX) and its glints'
    (``mitsuba_scene.gloss``); the preview traces light through it as a smooth skin (``boundary_bsdf``)."""
    if material.transmission >= TRANSMISSIVE:
        return float(material.transmission_roughness)
    return float(material.clearcoat_roughness if material.clearcoat > 0 else material.roughness)
