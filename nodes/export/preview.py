"""The ``preview`` node: a path-traced, denoised PNG of the shaded scene (Mitsuba 3, ``scalar_rgb``, Intel Open
Image Denoise) — SPEC §4.

Name the node ``preview``: the engine writes an ``Image`` output as ``<node id>.png``.
"""

from __future__ import annotations

import functools

from nodegraph.cost import Cost, CostQuery, Lever, estimated_by, gib
from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Image

from ..values import ShadedScene
from .mitsuba_scene import load_renderer
from .studio import AMBIENT, SETTINGS


def load_libraries() -> None:
    """The preview's ``overlap``: every native library its render loads, loaded before a run starts the instances
    beside it (``load_renderer``), SciPy's spatial module too, which the scene's hulls import
    (``mitsuba_scene.hull_vertices``), and Pillow's, which writes the table's texture (``studio.wood_png``).
    Without them, a run whose upstream was cached hung for good: the preview importing SciPy's (or Pillow's)
    libraries while the export beside it loaded USD's (the loader's lock against the GIL); the export's own, USD's,
    are its ``NodeSpec.libraries``."""
    load_renderer()
    import PIL.Image  # noqa: F401 - loaded for its libraries
    import PIL.PngImagePlugin  # noqa: F401
    import scipy.spatial  # noqa: F401 - loaded for its libraries


# the process's memory while the preview renders, above Python and the engine (``nodegraph.cost.PROCESS_BYTES``),
# for the cost estimate before any work: Mitsuba and the libraries the run has loaded by then, its scene (per mesh
# face of the elements: the shaded meshes the run holds and the renderer's copy), its film and the denoiser's guides
# (3 float RGBA buffers per pixel). The run's peak is here; fitted to the peaks of the rice bowl, the ikura don and the
# onigiri, full size and drafts (18,000–3,500,000 faces): each within 10 % (benchmarks/bench_cost.py)
RENDERER_BYTES = 490 * 2**20
BYTES_PER_FACE = 480
BYTES_PER_PIXEL = 48


# its CPU seconds, for the estimate before any work: a start (loading the scene, the guides, the glints' pass,
# denoising) and each sample of each megapixel, fitted to the previews of the scene table (benchmarks/measured/
# scenes.jsonl: rice bowl, ikura don, onigiri, kakigori, rice + chestnut within 10 %, the lying cylinder 33 % under,
# sushi 45 % over)
CPU_START = 4.0
CPU_PER_SAMPLE_MEGAPIXEL = 8.0


def _cost(q: CostQuery) -> Cost:
    """Its memory and CPU seconds from the scene's faces, the pixels and the samples; its levers: the samples for its
    time, the pixels for its memory (``cost.limit_over``)."""
    elements, faces = q.elements("scene"), q.faces("scene")
    width, height, samples = q.params["width"], q.params["height"], q.params["samples"]
    pixels = width * height
    scene = RENDERER_BYTES + int((elements or 0) * (faces or 0) * BYTES_PER_FACE)
    seconds = CPU_START + CPU_PER_SAMPLE_MEGAPIXEL * samples * pixels / 1e6

    def fewer_samples(budget: float) -> str:
        """The samples that keep its seconds within ``budget`` at these pixels."""
        kept = int((budget - CPU_START) / (CPU_PER_SAMPLE_MEGAPIXEL * pixels / 1e6))
        return f"samples ≤ {kept:,}" if kept >= 1 else f"fewer pixels than {width:,} × {height:,}"

    def fewer_pixels(budget: float) -> str:
        """The pixels that keep its memory within ``budget`` bytes with this scene."""
        kept = int((budget - scene) / BYTES_PER_PIXEL)
        if kept < 16 * 16:  # the smallest picture its range allows
            return f"fewer or simpler elements (the scene alone holds {gib(scene)})"
        return f"width × height ≤ {kept:,} px"

    return Cost(
        elements=elements,
        faces=faces,
        memory=scene + pixels * BYTES_PER_PIXEL,
        seconds=seconds,
        what=f"a {width:,} × {height:,} px preview at {samples} samples",
        time_lever=Lever("samples", fewer_samples),
        memory_lever=Lever("width", fewer_pixels),
    )


@estimated_by(_cost)
@node(
    "preview",
    # Mitsuba renders in its own threads with the GIL released, and so does the glints' blur (a numba kernel,
    # nogil, not parallel): the run computes what does not need the preview (export, measure) in a second thread
    # meanwhile (nodegraph.executor.Beside), started once every library the preview loads is loaded
    # (load_libraries: USD's loading in the export beside deadlocked against Mitsuba loading a plugin)
    overlap=load_libraries,
    inputs={"scene": In(ShadedScene, "shaded meshes with materials and per-vertex CDRF σ")},
    outputs={"image": Out(Image, "8-bit sRGB render")},
    params={
        "width": Param(int, 1280, "image width", range=(16, 4096), units="px"),
        "height": Param(int, 720, "image height", range=(16, 4096), units="px"),
        # 3: priced against 256 spp at depth 128 on the main job's eggs over rice (benchmarks/bench_preview.py
        # --budget; docs/accuracy.md, "Preview cost"): 5 spp 18.40 dB / SSIM 0.406 / 54.1 CPU s, 4 spp 18.09 / 0.390 /
        # 41.4, 3 spp 17.79 / 0.370 / 30.8, 2 spp 17.29 / 0.345 / 24.6. The image pass is ≈ 8 CPU s per sample: the
        # eggs hold it (their red light walks 16–64 bounces inside), so its samples are the lever.
        "samples": Param(int, 3, "samples per pixel (noise vs time; see benchmarks/bench_preview.py)", range=(1, 4096)),
        "denoise": Param(bool, True, "Intel Open Image Denoise with albedo + normal guides (pyoidn)"),
        "subsurface": Param(
            bool,
            True,
            "light under the skin: a scattering medium inside each rice grain (behind its wet film, whose sheen is "
            "a pass of its own) and ikura yolk (behind a dielectric boundary) (volpath; mean free path and albedo "
            "from the material's subsurface radius and colour); off: the thin principled surface with the CDRF "
            "translucency per vertex",
        ),
        "elevation": Param(float, 40.0, "camera elevation above the horizon", range=(-89.0, 89.0), units="degrees"),
        "azimuth": Param(float, 20.0, "camera azimuth (0 looks along +y)", range=(-360.0, 360.0), units="degrees"),
        "fov": Param(float, 35.0, "horizontal field of view", range=(1.0, 150.0), units="degrees"),
        "margin": Param(
            float,
            0.1,
            "framing: share of the half-frame left free around the scene on its tightest side (fitted to the "
            "scene's vertices as seen by the camera, so it follows any change of the scene)",
            range=(0.0, 0.9),
        ),
        "offset": Param(
            tuple[float, float],
            (0.0, 0.0),
            "framing: where the scene's centre sits, in half-frames right and up from the frame's centre (−0.33, 0: "
            "on the left third line, as a photographer composes by the rule of thirds); the fit leaves it room",
            range=(-0.8, 0.8),
        ),
        "f_stop": Param(
            float,
            5.6,
            "depth of field: the lens's f-number as on a full-frame camera with this field of view, in the scene's "
            "millimetres (5.6: the back of a bowl softens, its front stays sharp); 0: a pinhole, all sharp",
            range=(0.0, 64.0),
        ),
        "focus": Param(
            float,
            0.25,
            "the plane in focus: this quantile of the subject's depths from the camera (0 its nearest point, 1 its "
            "farthest; a food photographer focuses on the front of the dish)",
            range=(0.0, 1.0),
        ),
        "ambient": Param(
            float,
            AMBIENT,
            "radiance of the studio's uniform ambient (its walls): lights what the softboxes miss; the shade node's "
            "baked_ambient lights only the exported vertex colours",
            range=(0.0, 10.0),
        ),
        "setting": Param(
            str,
            "sweep",
            "what the subject stands on: 'sweep', a seamless backdrop of warm paper (a packshot), or 'table', a table "
            "top of oiled oak boards (studio.wood_texture) filling the frame behind the subject",
            choices=SETTINGS,
        ),
        "sun_direction": Param(
            tuple[float, float, float],
            (-0.45, -0.6, 0.75),
            "direction towards the studio's key softbox (match shade's key light)",
            range=(-1.0, 1.0),
        ),
    },
)
def preview(
    ctx,
    scene,
    *,
    width,
    height,
    samples,
    denoise,
    subsurface,
    elevation,
    azimuth,
    fov,
    margin,
    offset,
    f_stop,
    focus,
    ambient,
    setting,
    sun_direction,
):
    """Mitsuba path tracing of the materials in a procedural studio (key, fill, rim, a sweep or a table;
    ``studio``) through a thin lens, denoised; the same scene and parameters give the same bytes."""
    import numpy as np

    from .mitsuba_scene import Camera, render

    if not np.linalg.norm(sun_direction) > 0:
        raise ValueError("sun_direction: a zero vector has no direction")
    camera = Camera(elevation, azimuth, fov, margin, f_stop, focus, tuple(offset))
    quiet_interrupt()
    return Image(
        render(
            scene,
            camera,
            width,
            height,
            samples,
            sun_direction,
            denoised=denoise,
            subsurface=subsurface,
            ambient=ambient,
            setting=setting,
        )
    )


INTERRUPT_NOTE = "Received interrupt signal"  # what Mitsuba logs as Ctrl-C cancels its render


def quiet_interrupt() -> None:
    """Keep Mitsuba's own note of a Ctrl-C (a red 'WARN … Received interrupt signal, winding down..' line) out of a
    stopped run's output, which says it was interrupted in its one line; every other message of Mitsuba's logger
    passes as before. Installed once per process, around the logger's appenders."""
    import mitsuba as mi

    quiet = _quiet_appender()
    logger = mi.logger()
    appenders = [logger.appender(i) for i in range(logger.appender_count())]
    if any(isinstance(a, quiet) for a in appenders):
        return
    logger.clear_appenders()
    for appender in appenders:
        logger.add_appender(quiet(appender))


@functools.cache
def _quiet_appender() -> type:
    """A Mitsuba appender that passes on what it gets to another, less ``INTERRUPT_NOTE``."""
    import mitsuba as mi

    class Quiet(mi.Appender):
        def __init__(self, inner):
            super().__init__()
            self.inner = inner

        def append(self, level, text):
            if INTERRUPT_NOTE not in text:
                self.inner.append(level, text)

        def log_progress(self, progress, name, formatted, eta, ptr=None):
            self.inner.log_progress(progress, name, formatted, eta, ptr)

    return Quiet
