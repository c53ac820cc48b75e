"""Preview accuracy vs time — SPEC §4 preview: samples per pixel × OIDN denoising on/off against a 1,024-spp
reference (PSNR and SSIM, scikit-image) and the wall time of a 1280 × 720 preview.

    python benchmarks/bench_preview.py [--quick] [--cache-dir DIR]
    python benchmarks/bench_preview.py --ice [--quick] [--cache-dir DIR]    # kakigori ice vs path length
    python benchmarks/bench_preview.py --sss [--quick] [--cache-dir DIR]    # subsurface media × depth × spp
    python benchmarks/bench_preview.py --highlights [--quick]   # default preview: time, determinism, highlights
    python benchmarks/bench_preview.py --budget 10:64,8:48:4:2 [--save DIR]  # spp:depth[:glints[:guides[:media[:rr]]]]
    python benchmarks/bench_preview.py --budget 5:64,4:64,3:64 --recipe rice_bowl  # another recipe of graphs/
    python benchmarks/bench_preview.py --time 2 [--save PNG] [--quick]  # the default preview alone: time, same bytes
    python benchmarks/bench_preview.py --passes [--quick]       # CPU seconds of each pass of the default preview
    python benchmarks/bench_preview.py --bokeh 64 [--save PNG]  # out-of-focus glints: dots, energy vs the lens

The scene is the main job's (``graphs/ikura_don.yaml`` up to ``shade``, from the cache; computed the first
time), seen by its preview camera. Quality is measured in a window of the 1280 × 720 frame over the
eggs and rice (the hardest pixels: caustics inside the eggs, light through the grains; the table around
the bowl is easier), so the reference stays affordable on 2 cores; the denoiser sees the same pixel scale
as in the full frame. Times are the whole ``preview`` path at 1280 × 720 (PLY files, scene load, render,
guide pass, denoising). ``--quick``: a small synthetic scene and a 64-spp reference (seconds).
``--ice``: the kakigori mound (``graphs/kakigori.yaml``, reduced sizes with ``--quick``) all in plain ice, its
pixels' mean linear luminance against the same mound in a white diffuse material under the same light, and the
render time, per path length (the path tracer's ``max_depth``), with each flake a medium behind no skin
(subsurface on, the preview's default) and a thin diffuser (off): why ice got ``mitsuba_scene.MAX_DEPTH_FLAKES``.
Writes benchmarks/results/bench_preview.{md,png} (or under $NODEGRAPH_BENCH_RESULTS; the plot needs matplotlib).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from machine import conditions

ROOT = Path(__file__).resolve().parents[1]


def main_job_scene(cache_dir: Path | None, name: str = "ikura_don"):
    """A recipe's shaded scene (the ikura don's by default) and its preview camera (from the recipe)."""
    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe
    from nodes.export.mitsuba_scene import Camera

    recipe = load_recipe(ROOT / "graphs" / f"{name}.yaml", default_registry(), [])
    result = run_recipe(recipe, outputs=["shade.scene"], cache=Cache(cache_dir or default_cache_dir()))
    p = recipe.nodes["preview"].params
    camera = Camera(
        p["elevation"], p["azimuth"], p["fov"], p["margin"], p["f_stop"], p["focus"], tuple(p.get("offset", (0.0, 0.0)))
    )
    return result.output("shade.scene"), camera, p


def quick_scene():
    """A few capsule grains and eggs in a bowl (``scene_builders.small_food_scene``, as the tests use)."""
    from scene_builders import small_food_scene

    from nodes.export.mitsuba_scene import Camera
    from nodes.export.preview import preview
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade

    scene = shade.call(**small_food_scene(), material=cooked_material())
    params = preview.resolve_params({})
    return scene, Camera(50.0, 20.0, 35.0, 0.1, params["f_stop"], params["focus"]), params


KAKIGORI_QUICK = ["cup.size=10.0", "cup.depth=8.0", "cup.mound=12.0"]


def ice_vs_depth(quick: bool, cache_dir: Path | None) -> str:
    """The kakigori mound in plain ice against white diffuse, per path length: luminance ratio and render time."""
    import dataclasses

    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe
    from nodes.export import mitsuba_scene as ms
    from nodes.shading.materials import ice_materials, is_ice
    from nodes.values import Material

    recipe = load_recipe(ROOT / "graphs" / "kakigori.yaml", default_registry(), KAKIGORI_QUICK if quick else [])
    result = run_recipe(recipe, outputs=["shade.scene"], cache=Cache(cache_dir or default_cache_dir()))
    scene = result.output("shade.scene")
    p = recipe.nodes["preview"].params
    camera = ms.Camera(p["elevation"], p["azimuth"], p["fov"], p["margin"])
    width, height, spp = (96, 72, 8) if quick else (240, 180, 8)

    def luminance(material: Material, depth: int, media: bool = False) -> tuple[np.ndarray, float, float]:
        materials = tuple(material if is_ice(m) else m for m in scene.materials)
        description = dataclasses.replace(scene, materials=materials)
        t, c = time.perf_counter(), cpu_seconds()
        layers = ms.render_layers(
            description, camera, width, height, spp, p["sun_direction"], max_depth=depth, subsurface=media
        )
        return layers.noisy() @ np.array([0.2126, 0.7152, 0.0722]), time.perf_counter() - t, cpu_seconds() - c

    white, _, _ = luminance(Material("white", base_color=(0.9, 0.9, 0.9), roughness=1.0), ms.MAX_DEPTH)
    black, _, _ = luminance(Material("black", base_color=(0.0, 0.0, 0.0), roughness=1.0), ms.MAX_DEPTH)
    mound = white - black > 0.2
    plain = ice_materials((0.75, 0.02, 0.06))[0]
    lines = [
        f"Kakigori ({'reduced' if quick else 'full'} recipe) in plain ice: mean linear luminance of its "
        f"{int(mound.sum())} pixels / the same mound in white diffuse (0.9), {width}×{height}, {spp} spp; "
        f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores",
        "",
        "| ice | max_depth | ice / white | render wall (s) | render CPU (s) |",
        "|---|---|---|---|---|",
    ]
    for media in (True, False):
        for depth in (10, 32, 64, 128, 256):
            ice, wall, cpu = luminance(plain, depth, media)
            kind = "medium, no skin (subsurface on)" if media else "thin diffuser (subsurface off)"
            lines.append(
                f"| {kind} | {depth} | {ice[mound].mean() / white[mound].mean():.3f} | {wall:.1f} | {cpu:.1f} |"
            )
            print(lines[-1], flush=True)
    return "\n".join(lines)


def sss_cost(quick: bool, cache_dir: Path | None) -> str:
    """Subsurface scattering on / off × path depth × spp (OIDN on) against a converged render with the media: PSNR
    and SSIM over the whole frame, wall and CPU time of the whole preview (PLY files, load, render, guides, OIDN)."""
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    from nodes.export.mesh_files import linear_to_srgb8
    from nodes.export.mitsuba_scene import render, render_layers, tone_map

    if quick:
        scene, camera, params = quick_scene()
        width, height, reference_spp, spps, depths = 320, 180, 256, (4, 12), (10, 32)
    else:
        scene, camera, params = main_job_scene(cache_dir)
        width, height, reference_spp, spps, depths = 640, 360, 256, (4, 12, 32), (10, 32, 64)
    sun = params["sun_direction"]
    t = time.perf_counter()
    truth = render_layers(scene, camera, width, height, reference_spp, sun, 1, None, 128, subsurface=True)
    reference = linear_to_srgb8(tone_map(truth.noisy()))
    reference_time = time.perf_counter() - t
    print(f"reference: {reference_spp} spp, depth 128, media on, {reference_time:.0f} s", flush=True)
    rows = []
    for subsurface in (False, True):
        for depth in depths if subsurface else depths[:1]:
            for spp in spps:
                t, c = time.perf_counter(), cpu_seconds()
                image = render(scene, camera, width, height, spp, sun, True, 0, subsurface, depth)
                wall, cpu = time.perf_counter() - t, cpu_seconds() - c
                psnr = peak_signal_noise_ratio(reference, image, data_range=255)
                ssim = structural_similarity(reference, image, channel_axis=2, data_range=255)
                rows.append((subsurface, depth, spp, psnr, ssim, wall, cpu))
                print(f"  media {subsurface}, depth {depth}, {spp} spp: {psnr:.1f} dB, SSIM {ssim:.3f}, {wall:.1f} s")
    load = os.getloadavg()[0]
    lines = [
        f"Preview cost of {'a synthetic scene' if quick else 'the ikura don (main job)'} at {width}×{height}, OIDN on: "
        f"PSNR/SSIM of the whole frame against {reference_spp} spp with media, depth 128 ({reference_time:.0f} s); "
        f"time = the whole preview; CPU s / {os.cpu_count()} ≈ the time on {os.cpu_count()} free cores; load "
        f"average {load:.2f} on {os.cpu_count()} cores",
        "",
        "| media (SSS) | path depth | spp | PSNR (dB) | SSIM | wall (s) | CPU (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {'on' if m else 'off'} | {d} | {spp} | {psnr:.1f} | {ssim:.3f} | {wall:.1f} | {cpu:.1f} |"
        for m, d, spp, psnr, ssim, wall, cpu in rows
    ]
    return "\n".join(lines)


def highlights(quick: bool, cache_dir: Path | None) -> str:
    """The default preview (media on, OIDN): CPU and wall time of the whole preview and its determinism; and in the
    eggs-over-rice window, the highlight energy (linear luminance above the converged render's 99th percentile,
    summed) of the noisy and the denoised render against the converged one: does the denoiser keep the highlights?"""
    from nodes.export.mitsuba_scene import Crop, render, render_layers

    scene, camera, params = quick_scene() if quick else main_job_scene(cache_dir)
    width, height, spp, sun = params["width"], params["height"], params["samples"], params["sun_direction"]
    media = params["subsurface"]
    crop, reference_spp = Crop(544, 306, 192, 108), 256
    if quick:
        width, height, crop, reference_spp = 320, 180, Crop(112, 63, 96, 54), 64
    t, c = time.perf_counter(), cpu_seconds()
    first = render(scene, camera, width, height, spp, sun, True, 0, media)
    wall, cpu = time.perf_counter() - t, cpu_seconds() - c
    second = render(scene, camera, width, height, spp, sun, True, 0, media)
    layers = render_layers(scene, camera, width, height, spp, sun, 0, crop, subsurface=media)
    truth = render_layers(scene, camera, width, height, reference_spp, sun, 1, crop, subsurface=media).noisy()
    weights = np.array([0.2126, 0.7152, 0.0722], np.float32)
    threshold = float(np.percentile(truth @ weights, 99.0))

    def energy(color):
        luminance = color @ weights
        return float(np.maximum(luminance - threshold, 0.0).sum()), int((luminance > threshold).sum())

    rows = [
        ("noisy", layers.noisy()),
        ("denoised (OIDN)", layers.denoised()),
        (f"converged ({reference_spp} spp)", truth),
    ]
    load = os.getloadavg()[0]
    lines = [
        f"Default preview of {'a synthetic scene' if quick else 'the ikura don (main job)'} at {width}×{height}, "
        f"{spp} spp, media {'on' if media else 'off'}, OIDN: wall {wall:.1f} s, CPU {cpu:.1f} s (CPU s / "
        f"{os.cpu_count()} = {cpu / (os.cpu_count() or 1):.1f} s on {os.cpu_count()} free cores; load average "
        f"{load:.2f}); identical bytes on a second render: {np.array_equal(first, second)}",
        "",
        f"Highlights in the {crop.width}×{crop.height} window at ({crop.x}, {crop.y}): luminance above the converged "
        f"render's 99th percentile ({threshold:.3f})",
        "",
        "| render | highlight energy | highlight pixels |",
        "|---|---|---|",
    ]
    lines += [f"| {name} | {energy(color)[0]:.2f} | {energy(color)[1]} |" for name, color in rows]
    return "\n".join(lines)


def timed(quick: bool, cache_dir: Path | None, repeat: int, save: Path | None) -> str:
    """The default preview alone (the preview node's parameters, studio and lens included): wall and CPU time of each
    of ``repeat`` renders, whether they gave the same bytes; the first picture written to ``save``."""
    from nodes.export.mitsuba_scene import render

    scene, camera, params = quick_scene() if quick else main_job_scene(cache_dir)
    width, height, spp, sun = params["width"], params["height"], params["samples"], params["sun_direction"]
    if quick:
        width, height = 320, 180
    runs, images = [], []
    for _ in range(repeat):
        t, c = time.perf_counter(), cpu_seconds()
        images.append(render(scene, camera, width, height, spp, sun, True, 0, params["subsurface"]))
        runs.append((time.perf_counter() - t, cpu_seconds() - c, os.getloadavg()[0]))
    if save is not None:
        from PIL import Image

        Image.fromarray(images[0]).save(save)
    n = os.cpu_count() or 1
    times = "; ".join(f"wall {w:.1f} s, CPU {c:.1f} s (CPU s / {n} = {c / n:.1f} s), load {a:.2f}" for w, c, a in runs)
    same = all(np.array_equal(images[0], image) for image in images[1:])
    return (
        f"Default preview of {'a synthetic scene' if quick else 'the ikura don (main job)'} at {width}×{height}, "
        f"{spp} spp, f/{camera.f_stop:g}: {times}; identical bytes across the {repeat} renders: {same}"
    )


def budget(
    configs: str, quick: bool, cache_dir: Path | None, save: Path | None = None, recipe: str = "ikura_don"
) -> str:
    """The whole default preview (OIDN, glints) at each ``spp:depth[:glint spp[:guide spp[:media 0/1[:rr depth]]]]``
    of ``configs``: CPU and wall time of the full frame, PSNR/SSIM/FLIP in the window at the frame's centre (the
    main job's eggs over rice; 15 % of each side) against 256 spp (64 with ``--quick``) at depth 128 with media, and
    the full frame's FLIP against the first config's (what a viewer sees change from it), beside the first config at
    seed 1 (what changes at the same samples: the noise floor, below which fewer samples change nothing a reseed would
    not); each full frame written to ``save``/<config>.png if given. ``recipe``: a recipe of graphs/ by name."""
    import flip_evaluator as flip
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    from nodes.export import mitsuba_scene as ms
    from nodes.export.mesh_files import linear_to_srgb8
    from nodes.export.mitsuba_scene import Crop, render, render_layers, tone_map

    scene, camera, params = quick_scene() if quick else main_job_scene(cache_dir, recipe)
    width, height, sun, media = params["width"], params["height"], params["sun_direction"], params["subsurface"]
    window = (round(width * 0.15), round(height * 0.15))  # 192 × 108 at 1280 × 720: the main job's eggs over rice
    crop = Crop((width - window[0]) // 2, (height - window[1]) // 2, *window)
    reference_spp = 256
    if quick:
        width, height, crop, reference_spp = 320, 180, Crop(112, 63, 96, 54), 64
    t = time.perf_counter()
    truth = render_layers(scene, camera, width, height, reference_spp, sun, 1, crop, 128, subsurface=media)
    reference = linear_to_srgb8(tone_map(truth.noisy()))
    reference_time = time.perf_counter() - t
    rows, first = [], None
    defaults = (ms.HIGHLIGHT_SPP, ms.GUIDE_SPP, ms.RR_DEPTH)
    listed = configs.split(",")
    for k, config in enumerate([*listed, listed[0]]):  # the first again at seed 1: the noise floor
        seed = int(k == len(listed))
        fields = [int(v) for v in config.split(":")]
        spp, depth, glint_spp, guide_spp, with_media, rr_depth = (
            fields + [*defaults[:2], int(media), defaults[2]][len(fields) - 2 :]
        )
        ms.HIGHLIGHT_SPP, ms.GUIDE_SPP, ms.RR_DEPTH = glint_spp, guide_spp, rr_depth
        try:
            t, c = time.perf_counter(), cpu_seconds()
            frame = render(scene, camera, width, height, spp, sun, True, seed, bool(with_media), depth)
            wall, cpu = time.perf_counter() - t, cpu_seconds() - c
            if save is not None:
                from PIL import Image

                save.mkdir(parents=True, exist_ok=True)
                Image.fromarray(frame).save(save / f"{config.replace(':', '_')}{'_seed1' * seed}.png")
            layers = render_layers(scene, camera, width, height, spp, sun, seed, crop, depth, bool(with_media))
        finally:
            ms.HIGHLIGHT_SPP, ms.GUIDE_SPP, ms.RR_DEPTH = defaults
        image = linear_to_srgb8(tone_map(layers.denoised()))
        psnr = peak_signal_noise_ratio(reference, image, data_range=255)
        ssim = structural_similarity(reference, image, channel_axis=2, data_range=255)
        first = frame if first is None else first
        window_flip, frame_flip = (
            float(flip.evaluate(a / 255.0, b / 255.0, "LDR")[1])
            for a, b in (
                (reference.astype(np.float32), image.astype(np.float32)),
                (first.astype(np.float32), frame.astype(np.float32)),
            )
        )
        rows.append(
            f"| {spp}{' (seed 1)' * seed} | {depth} | {rr_depth} | {glint_spp} | {guide_spp} | "
            f"{'on' if with_media else 'off'} | "
            f"{psnr:.2f} | {ssim:.3f} | {window_flip:.4f} | {frame_flip:.4f} | {wall:.1f} | {cpu:.1f} | "
            f"{cpu / (os.cpu_count() or 1):.1f} |"
        )
        print(rows[-1], flush=True)
    n = os.cpu_count()
    return "\n".join(
        [
            f"Default preview of {'a synthetic scene' if quick else recipe} at {width}×{height} "
            f"(media {'on' if media else 'off'}, OIDN, glints): PSNR/SSIM in the {crop.width}×{crop.height} window "
            f"at ({crop.x}, {crop.y}) against {reference_spp} spp at depth 128 ({reference_time:.0f} s); load average "
            f"{os.getloadavg()[0]:.2f} on {n} cores",
            "",
            f"| spp | path depth | rr depth | glint spp | guide spp | media (SSS) | PSNR (dB) | SSIM | FLIP | "
            f"FLIP to the first (frame) | wall (s) | CPU (s) | CPU s / {n} |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
            *rows,
        ]
    )


def passes(quick: bool, cache_dir: Path | None) -> str:
    """CPU and wall seconds of each pass of the default preview (scene load, path-traced image, the denoiser's
    guides, the glints, rice's film), the same calls ``mitsuba_scene.render_layers`` makes, timed one by one."""
    import tempfile

    import mitsuba as mi

    from nodes.export import mitsuba_scene as ms

    scene, camera, params = quick_scene() if quick else main_job_scene(cache_dir)
    width, height, spp = (
        (320, 180, params["samples"]) if quick else (params["width"], params["height"], params["samples"])
    )
    mi.set_variant("scalar_rgb")
    rows = []

    def clock(name, work):
        cpu, wall = cpu_seconds(), time.perf_counter()
        out = work()
        rows.append(f"| {name} | {cpu_seconds() - cpu:.1f} | {time.perf_counter() - wall:.1f} |")
        return out

    with tempfile.TemporaryDirectory(prefix="bench_preview_") as folder:
        description, set_up = clock(
            "scene description (PLY files)",
            lambda: ms._described(
                scene,
                Path(folder),
                camera,
                width,
                height,
                spp,
                params["sun_direction"],
                None,
                None,
                params["subsurface"],
                params["ambient"],
            ),
        )
        loaded = clock("scene load", lambda: mi.load_dict(description, optimize=False))
        integrator = description["integrator"]
        image = clock(
            f"image: {spp} spp, {integrator['type']} depth {integrator['max_depth']}", lambda: mi.render(loaded, seed=0)
        )
        guides = mi.load_dict({"type": "aov", "aovs": ms.ALBEDO_AOV})
        aov = clock(
            f"denoiser guides: {min(spp, ms.GUIDE_SPP)} spp",
            lambda: mi.render(loaded, integrator=guides, seed=0, spp=min(spp, ms.GUIDE_SPP)),
        )
        color, aov = np.asarray(image, np.float32)[..., :3] * np.float32(ms.EXPOSURE), np.asarray(aov, np.float32)
        layers = ms.Layers(np.maximum(color, 0.0), np.clip(aov[..., 0:3], 0, 1), np.clip(aov[..., 3:6], -1, 1), color)
        clock(f"denoiser (OIDN, quality {ms.DENOISE_QUALITY})", lambda: ms.denoise(layers))
        window = ms.glints_window(set_up, camera, width, height, ms.glints_core(description))
        pinhole = clock(
            "glints: scene load", lambda: mi.load_dict(ms.highlight_dict(scene, description, window), optimize=False)
        )
        part = clock(
            f"glints: {ms.HIGHLIGHT_SPP} spp, one bounce, pinhole, in {window.width} × {window.height} px",
            lambda: np.asarray(mi.render(pinhole, seed=0), np.float32),
        )
        if params["subsurface"] and any(ms.has_film(m) for m in scene.materials):  # rice's sheen: a pass of its own
            sheen = clock(
                "film: scene load",
                lambda: mi.load_dict(ms.highlight_dict(scene, description, window, film=True), optimize=False),
            )
            clock(
                f"film: {ms.FILM_SPP} spp, one bounce, pinhole, in {window.width} × {window.height} px",
                lambda: mi.render(sheen, seed=0, spp=ms.FILM_SPP),
            )
        depth = mi.load_dict({"type": "aov", "aovs": ms.DEPTH_AOV})
        distance = clock(
            "glints: depth, 1 spp", lambda: np.asarray(mi.render(pinhole, integrator=depth, seed=0, spp=1), np.float32)
        )
        sharp, far = np.zeros((height, width, 3), np.float32), np.zeros((height, width), np.float32)
        sharp[window.y : window.y + window.height, window.x : window.x + window.width] = part[..., :3]
        far[window.y : window.y + window.height, window.x : window.x + window.width] = distance[..., 0]
        frame = ms.Crop(0, 0, width, height)
        clock(
            "glints: the lens's blur (bokeh)",
            lambda: ms.defocus(sharp, far, description["sensor"], width, height, frame),
        )
    subject = "synthetic scene" if quick else "main job"
    head = f"Passes of the default preview, {width} × {height}, {subject}; {conditions()}"
    return "\n".join([head, "", "| pass | CPU s | wall s |", "|---|---|---|", *rows])


def bokeh(quick: bool, cache_dir: Path | None, reference_spp: int, save: Path | None) -> str:
    """Out-of-focus glints in the default preview (docs/look.md, "Bokeh, not dots"). The circle of confusion of each
    pixel (its radius in pixels, from a pinhole depth pass of the scene); in the final 8-bit picture the isolated
    bright dots: pixels whose sRGB luminance (0–1) exceeds its 5 × 5 neighbourhood's median by more than 0.2, out of
    focus (circle of confusion ≥ 2 px) and in focus (< 1 px); the glints' layer (linear luminance) against the
    glints' pass through the thin lens at ``reference_spp`` (what the lens converges to): its energy out of and in
    focus, the highlight energy in focus (luminance above the reference's 99th percentile there, summed: the
    ``--highlights`` measure) and, out of focus, the L1 distance of the two smoothed over 5 × 5 pixels relative to
    the reference's. Works on this and on older code (``PYTHONPATH``): it only calls ``render_layers``,
    ``scene_dict`` and ``highlight_dict``."""
    import tempfile

    import mitsuba as mi
    from scipy.ndimage import median_filter, uniform_filter

    from nodes.export import mitsuba_scene as ms
    from nodes.export import studio
    from nodes.export.mesh_files import linear_to_srgb8

    scene, camera, params = quick_scene() if quick else main_job_scene(cache_dir)
    width, height, spp, sun = params["width"], params["height"], params["samples"], params["sun_direction"]
    if quick:
        width, height = 320, 180
    media, ambient = params["subsurface"], params["ambient"]
    runs = []
    for _ in range(2):
        t, c = time.perf_counter(), cpu_seconds()
        layers = ms.render_layers(scene, camera, width, height, spp, sun, 0, subsurface=media, ambient=ambient)
        image = linear_to_srgb8(ms.tone_map(layers.denoised()))
        runs.append((time.perf_counter() - t, cpu_seconds() - c, image))
    if save is not None:
        from PIL import Image

        Image.fromarray(runs[0][2]).save(save)
    mi.set_variant("scalar_rgb")
    weights = np.array([0.2126, 0.7152, 0.0722], np.float32)
    with tempfile.TemporaryDirectory(prefix="bench_bokeh_") as folder:
        description = ms.scene_dict(
            scene, Path(folder), camera, width, height, spp, sun, subsurface=media, ambient=ambient
        )
        sensor = description["sensor"]
        pinhole = {k: v for k, v in sensor.items() if k not in ("aperture_radius", "focus_distance")}
        depth_pass = {
            **{k: v for k, v in description.items() if k.startswith("shape_") or k == "backdrop"},
            "type": "scene",
            "integrator": {"type": "aov", "aovs": "distance:depth"},
            "sensor": pinhole | {"type": "perspective", "sampler": {"type": ms.SAMPLER, "sample_count": 1}},
        }
        depth_pass = {
            k: ({kk: vv for kk, vv in v.items() if kk != "interior"} if k.startswith("shape_") else v)
            for k, v in depth_pass.items()
        }
        distance = np.asarray(mi.render(mi.load_dict(depth_pass, optimize=False), seed=0), np.float64)[..., 0]
        lens = ms.highlight_dict(scene, description)
        lens["sensor"] = sensor | {"sampler": {"type": ms.SAMPLER, "sample_count": reference_spp}}
        lens["integrator"] = {"type": "path", "max_depth": 2}
        t, c = time.perf_counter(), cpu_seconds()
        converged = np.asarray(mi.render(mi.load_dict(lens, optimize=False), seed=1), np.float32)[..., :3]
        reference_cpu = cpu_seconds() - c
    converged = np.nan_to_num(converged, nan=0.0, posinf=0.0) @ weights * np.float32(ms.EXPOSURE)
    tan_x = np.tan(np.radians(camera.fov) / 2)
    tan_y = tan_x * height / width
    x = (2.0 * (np.arange(width) + 0.5) / width - 1.0) * tan_x
    y = (1.0 - 2.0 * (np.arange(height) + 0.5) / height) * tan_y
    depth = distance / np.sqrt(1.0 + x[None, :] ** 2 + y[:, None] ** 2)
    aperture, focus = studio.aperture_radius(camera.fov, camera.f_stop), float(sensor.get("focus_distance", 1.0))
    radius = aperture * np.abs(1.0 - focus / np.where(depth > 0, depth, focus)) / (focus * tan_x) * (width / 2)
    out, sharp = (radius >= 2.0) & (depth > 0), (radius < 1.0) & (depth > 0)
    luma = runs[0][2].astype(np.float64) @ weights / 255.0
    dots = (luma - median_filter(luma, size=5)) > 0.2
    glints = layers.highlights @ weights
    top = float(np.percentile(converged[sharp], 99.0))

    def highlight(color):
        return float(np.maximum(color[sharp] - top, 0.0).sum())

    smooth, truth = (uniform_filter(np.asarray(v, np.float64), 5)[out] for v in (glints, converged))
    n = os.cpu_count() or 1
    times = "; ".join(f"wall {w:.1f} s, CPU {c:.1f} s" for w, c, _ in runs)
    return "\n".join(
        [
            f"Default preview of {'a synthetic scene' if quick else 'the ikura don (main job)'} at {width}×{height}, "
            f"{spp} spp, f/{camera.f_stop:g}: {times} (load {os.getloadavg()[0]:.2f}, {n} cores); the same bytes "
            f"twice: {np.array_equal(runs[0][2], runs[1][2])}",
            f"Out of focus (circle of confusion ≥ 2 px): {int(out.sum())} px, max radius {radius[depth > 0].max():.1f}"
            f" px; in focus (< 1 px): {int(sharp.sum())} px",
            "",
            "| measure | out of focus | in focus |",
            "|---|---|---|",
            f"| isolated bright dots in the picture (luma − 5×5 median > 0.2) | {int(dots[out].sum())} | "
            f"{int(dots[sharp].sum())} |",
            f"| glints' energy (linear luminance, summed) | {glints[out].sum():.1f} | {glints[sharp].sum():.1f} |",
            f"| the lens at {reference_spp} spp ({reference_cpu:.0f} CPU s) | {converged[out].sum():.1f} | "
            f"{converged[sharp].sum():.1f} |",
            f"| highlight energy in focus (above {top:.3f}): glints / lens | | {highlight(glints):.1f} / "
            f"{highlight(converged):.1f} |",
            f"| L1 (5×5-smoothed) against the lens, relative | {np.abs(smooth - truth).sum() / truth.sum():.3f} | |",
        ]
    )


def cpu_seconds() -> float:
    """CPU time of this process (all threads): with other work on the machine, wall time alone misleads."""
    return time.process_time()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="small synthetic scene, 64-spp reference (seconds)")
    parser.add_argument("--cache-dir", type=Path, default=None, help="nodegraph cache holding the main job")
    parser.add_argument("--ice", action="store_true", help="kakigori ice brightness vs path length instead")
    parser.add_argument("--sss", action="store_true", help="subsurface media on/off × path depth × spp instead")
    parser.add_argument("--highlights", action="store_true", help="default preview: time and highlight energy")
    parser.add_argument(
        "--budget",
        default=None,
        help="spp:depth[:glint spp[:guide spp[:media 0/1[:rr depth]]]],...: time against quality",
    )
    parser.add_argument("--recipe", default="ikura_don", help="--budget: the recipe of graphs/ (name) to render")
    parser.add_argument("--time", type=int, default=0, metavar="N", help="the default preview alone, N renders: time")
    parser.add_argument("--passes", action="store_true", help="CPU seconds of each pass of the default preview")
    parser.add_argument(
        "--bokeh", type=int, default=0, metavar="SPP", help="out-of-focus glints against the lens at SPP samples"
    )
    parser.add_argument(
        "--save", type=Path, default=None, help="--time: the first render's PNG; --budget: a folder for each frame"
    )
    args = parser.parse_args()
    if args.bokeh:
        print(bokeh(args.quick, args.cache_dir, args.bokeh, args.save))
        return
    if args.passes:
        print(passes(args.quick, args.cache_dir))
        return
    if args.time:
        print(timed(args.quick, args.cache_dir, args.time, args.save))
        return
    if args.budget:
        print(budget(args.budget, args.quick, args.cache_dir, args.save, args.recipe))
        return
    if args.highlights:
        print(highlights(args.quick, args.cache_dir))
        return
    if args.sss:
        text = sss_cost(args.quick, args.cache_dir)
        print(text)
        out = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or Path(__file__).parent / "results")
        out.mkdir(parents=True, exist_ok=True)
        (out / f"bench_preview_sss{'_quick' if args.quick else ''}.md").write_text(text + "\n")
        return
    if args.ice:
        text = ice_vs_depth(args.quick, args.cache_dir)
        print(text)
        out = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or Path(__file__).parent / "results")
        out.mkdir(parents=True, exist_ok=True)
        (out / f"bench_preview_ice{'_quick' if args.quick else ''}.md").write_text(text + "\n")
        return
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    from nodes.export.mesh_files import linear_to_srgb8
    from nodes.export.mitsuba_scene import Crop, render, render_layers, tone_map

    if args.quick:
        scene, camera, params = quick_scene()
        width, height, crop = 320, 180, Crop(112, 63, 96, 54)
        # the default's own row is always in the grid: the accuracy report states it in bold
        spps = timed_spps = tuple(sorted({1, 4, int(params["samples"])}))
        reference_spp = 64
    else:
        scene, camera, params = main_job_scene(args.cache_dir)
        width, height, crop = 1280, 720, Crop(544, 306, 192, 108)
        reference_spp, spps, timed_spps = 1024, (1, 2, 4, 8, 10, 12, 16, 32), (2, 4, 8, 10, 12, 16)
    sun = params["sun_direction"]

    t = time.perf_counter()
    converged = render_layers(scene, camera, width, height, reference_spp, sun, 1, crop)
    reference = linear_to_srgb8(tone_map(converged.noisy()))
    reference_time = time.perf_counter() - t
    print(f"reference: {reference_spp} spp in {reference_time:.0f} s", flush=True)

    rows = []
    for spp in spps:
        layers = render_layers(scene, camera, width, height, spp, sun, 0, crop)
        for denoised in (False, True):
            image = linear_to_srgb8(tone_map(layers.denoised() if denoised else layers.noisy()))
            psnr = peak_signal_noise_ratio(reference, image, data_range=255)
            ssim = structural_similarity(reference, image, channel_axis=2, data_range=255)
            wall = cpu = float("nan")
            if spp in timed_spps:
                t, c = time.perf_counter(), cpu_seconds()
                render(scene, camera, width, height, spp, sun, denoised=denoised)
                wall, cpu = time.perf_counter() - t, cpu_seconds() - c
            rows.append((spp, denoised, psnr, ssim, wall, cpu))
            print(f"  {spp} spp, denoise {denoised}: {psnr:.1f} dB, SSIM {ssim:.3f}, {wall:.1f} s", flush=True)

    load = os.getloadavg()[0]
    lines = [
        f"Preview of {'a synthetic scene' if args.quick else 'the ikura don (main job)'}: PSNR/SSIM in the "
        f"{crop.width}×{crop.height} window at ({crop.x}, {crop.y}) of the {width}×{height} frame against "
        f"{reference_spp} spp ({reference_time:.0f} s); time = the whole preview at {width}×{height}; "
        f"CPU s / {os.cpu_count()} ≈ the time on {os.cpu_count()} free cores; load average {load:.2f} on "
        f"{os.cpu_count()} cores",
        "",
        "| spp | denoise | PSNR (dB) | SSIM | wall (s) | CPU (s) |",
        "|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {spp} | {'OIDN' if d else 'off'} | {psnr:.1f} | {ssim:.3f} | {wall:.1f} | {cpu:.1f} |"
        for spp, d, psnr, ssim, wall, cpu in rows
    ]
    text = "\n".join(lines)
    print(text)
    out = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or Path(__file__).parent / "results")
    out.mkdir(parents=True, exist_ok=True)
    suffix = "_quick" if args.quick else ""
    (out / f"bench_preview{suffix}.md").write_text(text + "\n")
    try:
        import matplotlib
    except ImportError:
        print("matplotlib not installed (pip install -e '.[bench]'): no plot")
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for denoised, marker in ((False, "o-"), (True, "s-")):
        pts = [(cpu / (os.cpu_count() or 1), psnr, spp) for spp, d, psnr, _, _, cpu in rows if d == denoised]
        pts = [p for p in pts if np.isfinite(p[0])]
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker, label="OIDN" if denoised else "no denoising")
            for x, y, spp in pts:
                ax.annotate(f"{spp}", (x, y), textcoords="offset points", xytext=(4, -10), fontsize=8)
    ax.axhline(30.0, color="k", ls=":", label="30 dB target")
    ax.set_xscale("log")
    ax.set_xlabel(f"preview time at {width}×{height} on {os.cpu_count()} free cores (CPU s / cores)")
    ax.set_ylabel(f"PSNR vs {reference_spp} spp (dB)")
    ax.set_title("Preview: samples per pixel × denoising")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / f"bench_preview{suffix}.png", dpi=120)
    print(f"wrote {out / f'bench_preview{suffix}.md'} and {out / f'bench_preview{suffix}.png'}")


if __name__ == "__main__":
    main()
