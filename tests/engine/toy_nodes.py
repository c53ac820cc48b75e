"""Small node types for engine tests (the engine must not depend on the real nodes): a plugin file
with its own value type, as a user's would be."""

import os
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nodegraph import In, Out, Param, loads_libraries, node
from nodegraph.rerun_log import log_value
from nodegraph.values import Image, Mesh, Table


@dataclass(frozen=True, eq=False)
class SphereSet:
    """Spheres (centre, radius): the toy nodes' own value type."""

    centers: np.ndarray
    radii: np.ndarray

    def __len__(self) -> int:
        return len(self.radii)


@log_value.register
def _(value: SphereSet, log) -> None:
    """A plugin's value type registers its own Rerun view."""
    import rerun as rr

    log.log("", rr.Points3D(value.centers.astype(np.float32), radii=value.radii.astype(np.float32)), static=True)


@node(
    "toy_points",
    random=True,
    outputs={"spheres": Out(SphereSet, "random spheres")},
    params={
        "count": Param(int, 10, "number of points", range=(1, 100_000)),
        "scale": Param(float, 1.0, "extent", range=(0.0, 100.0), units="mm"),
        "mode": Param(str, "cube", "distribution", choices=("cube", "ball")),
    },
)
def toy_points(ctx, *, count, scale, mode):
    """Random spheres in a cube or ball."""
    centers = ctx.rng.uniform(-scale, scale, size=(count, 3))
    if mode == "ball":
        centers /= np.maximum(1.0, np.linalg.norm(centers, axis=1, keepdims=True) / scale)
    return SphereSet(centers, ctx.rng.uniform(0.1, 0.2, count))


@node(
    "toy_shift",
    inputs={"spheres": In(SphereSet, "to move")},
    outputs={"spheres": Out(SphereSet, "moved")},
    params={"dx": Param(float, 0.0, "shift along x", range=(-10.0, 10.0), units="mm")},
)
def toy_shift(ctx, spheres, *, dx):
    """Move spheres along x."""
    return SphereSet(spheres.centers + np.array([dx, 0.0, 0.0]), spheres.radii)


@node(
    "toy_merge",
    inputs={"parts": In(SphereSet, "sets to merge", many=True)},
    outputs={"spheres": Out(SphereSet, "all spheres"), "stats": Out(Table, "count per part")},
)
def toy_merge(ctx, parts):
    """Concatenate sphere sets."""
    merged = SphereSet(np.concatenate([p.centers for p in parts]), np.concatenate([p.radii for p in parts]))
    return {"spheres": merged, "stats": Table({"count": np.array([len(p) for p in parts])})}


@node(
    "toy_mesh",
    outputs={"mesh": Out(Mesh, "a tetrahedron")},
    params={"size": Param(float, 1.0, "edge scale", range=(0.001, 10.0), units="mm")},
)
def toy_mesh(ctx, *, size):
    """A tetrahedron."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * size
    return Mesh(v, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


@node(
    "toy_measure",
    inputs={"mesh": In(Mesh, "mesh to measure")},
    outputs={"table": Out(Table, "vertex count")},
)
def toy_measure(ctx, mesh):
    """Count vertices."""
    return Table({"vertices": np.array([len(mesh.vertices)])})


@node(
    "toy_physics",
    effects=("gravity", "friction", "adhesion"),
    inputs={"spheres": In(SphereSet, "particles")},
    outputs={"spheres": Out(SphereSet, "after one step"), "effects": Out(Table, "effects seen")},
    params={"dt": Param(float, 0.01, "time step", range=(0.0, 1.0), units="s")},
)
def toy_physics(ctx, spheres, *, dt):
    """Drops particles under gravity if asked; reports the effects it was given."""
    centers = spheres.centers.copy()
    if ctx.wants("gravity"):
        centers[:, 2] -= 9.81 * dt * dt
    names = sorted(ctx.effects)
    return {
        "spheres": SphereSet(centers, spheres.radii),
        "effects": Table({"gravity": np.array([ctx.wants("gravity")]), "count": np.array([len(names)])}),
    }


@node("toy_fail", inputs={"spheres": In(SphereSet, "anything")}, outputs={"spheres": Out(SphereSet, "never")})
def toy_fail(ctx, spheres):
    """Logs two steps of a scalar, then always fails."""
    import rerun as rr

    for step in range(2):
        ctx.rerun.set_time("sim_step", step)
        ctx.rerun.log("energy", rr.Scalars(float(step)))
    raise ValueError("toy failure: radius must be positive")


@node("toy_stopped", inputs={"spheres": In(SphereSet, "anything")}, outputs={"spheres": Out(SphereSet, "never")})
def toy_stopped(ctx, spheres):
    """Logs a step, then is stopped inside compiled code: a signal's ``KeyboardInterrupt`` comes out of numba's
    dispatcher as a ``SystemError`` ("returned a result with an exception set")."""
    import rerun as rr

    ctx.rerun.set_time("sim_step", 0)
    ctx.rerun.log("energy", rr.Scalars(0.0))
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as stop:
        raise SystemError("CPUDispatcher(<function kernel>) returned a result with an exception set") from stop


@node(
    "toy_slow",
    inputs={"spheres": In(SphereSet, "passed through")},
    outputs={"spheres": Out(SphereSet, "same")},
    params={
        "seconds": Param(float, 0.0, "sleep", range=(0.0, 60.0), units="s"),
        "started": Param(str, "", "a folder: the node writes a file named by its process id there as it starts"),
    },
)
def toy_slow(ctx, spheres, *, seconds, started):
    """Sleeps, with progress and a per-step scalar on the sim_step timeline, then passes the spheres on. A
    test that interrupts a run waits for the file in ``started``: from then on the node is running."""
    import rerun as rr

    if started:
        Path(started).mkdir(parents=True, exist_ok=True)
        (Path(started) / str(os.getpid())).touch()
    with ctx.progress(10, "sleeping") as bar:
        for step in range(10):
            time.sleep(seconds / 10)
            ctx.rerun.set_time("sim_step", step)
            ctx.rerun.log("energy", rr.Scalars(float(10 - step)))
            bar.advance()
    return SphereSet(spheres.centers.copy(), spheres.radii.copy())


@node(
    "toy_scene",
    store=False,
    inputs={"spheres": In(SphereSet, "to copy")},
    outputs={"spheres": Out(SphereSet, "a copy")},
    params={"runs": Param(str, "", "a file: each run of the node appends a line to it")},
)
def toy_scene(ctx, spheres, *, runs):
    """Never cached (``store=False``, as a scene made in a second): a copy of the spheres; each run says so in
    ``runs``."""
    if runs:
        with open(runs, "a", encoding="utf-8") as out:
            out.write("ran\n")
    return SphereSet(spheres.centers.copy(), spheres.radii.copy())


_FIRST_LOAD_PAID = False  # toy_first_load: whether this process paid its first load


@node(
    "toy_first_load",
    inputs={"spheres": In(SphereSet, "to scale")},
    outputs={"spheres": Out(SphereSet, "radii scaled")},
    params={
        "scale": Param(float, 1.0, "radius factor", range=(0.0, 10.0)),
        "load_seconds": Param(float, 0.0, "what its first call in a process waits", range=(0.0, 60.0), units="s"),
        "trace": Param(str, "", "a file: each call appends 'load' when it paid the first load, then 'call'"),
    },
)
def toy_first_load(ctx, spheres, *, scale, load_seconds, trace):
    """Scales radii; its first call in a process first waits ``load_seconds``, as a node whose kernels numba
    loads from its cache does."""
    global _FIRST_LOAD_PAID
    lines = []
    if not _FIRST_LOAD_PAID:
        time.sleep(load_seconds)
        _FIRST_LOAD_PAID = True
        lines.append("load")
    if trace:
        with open(trace, "a") as file:
            file.write("".join(f"{line}\n" for line in [*lines, "call"]))
    return SphereSet(spheres.centers.copy(), spheres.radii * scale)


@node(
    "toy_sphere_mesh",
    inputs={"spheres": In(SphereSet, "centres")},
    outputs={"mesh": Out(Mesh, "one tetrahedron per sphere")},
)
def toy_sphere_mesh(ctx, spheres):
    """A tiny tetrahedron at each centre."""
    base = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * 0.1
    verts = (spheres.centers[:, None, :] + base[None]).reshape(-1, 3)
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])[None] + 4 * np.arange(len(spheres))[:, None, None]
    return Mesh(verts, faces.reshape(-1, 3))


@node(
    "toy_file_table",
    outputs={"table": Out(Table, "one row per line of the file")},
    params={"path": Param(str, doc="text file (.txt, .csv)", file=True)},
)
def toy_file_table(ctx, *, path):
    """The lengths of a text file's lines."""
    with open(path, encoding="utf-8") as handle:
        return Table({"length": np.array([len(line) for line in handle.read().splitlines()])})


@node(
    "toy_picture",
    inputs={"spheres": In(SphereSet, "to picture")},
    outputs={"image": Out(Image, "a 24 × 32 tile whose red is the spheres' mean x")},
)
def toy_picture(ctx, spheres):
    """A flat tile coloured by where the spheres are (a stand-in for a preview)."""
    red = int(np.clip(128 + 60 * spheres.centers[:, 0].mean(), 0, 255))
    return Image(np.tile(np.array([red, 40, 90], np.uint8), (24, 32, 1)))


_MEETING: dict[str, threading.Event] = {}  # toy_render and toy_busy meet here, by the name in their ``meet``
_MEETING_LOCK = threading.Lock()


def _meet(meet: str, me: str, other: str) -> None:
    """Say that ``me`` is running and wait for ``other`` to say so: true only of two nodes running at once."""
    if meet == "alone":
        return
    with _MEETING_LOCK:
        mine = _MEETING.setdefault(f"{meet}/{me}", threading.Event())
        theirs = _MEETING.setdefault(f"{meet}/{other}", threading.Event())
    mine.set()
    if not theirs.wait(5.0):
        raise RuntimeError(f"{me} ran alone: {other} did not run beside it within 5 s")


RENDER_PREPARED: list[bool] = []  # per call of toy_render's ``overlap``: was a thread beside it running already?


def _load_render_libraries() -> None:
    """toy_render's ``overlap`` (as the preview's ``load_renderer``): must run before anything runs beside it."""
    RENDER_PREPARED.append(any(t.name == "nodegraph-beside" for t in threading.enumerate()))


@node(
    "toy_render",
    overlap=_load_render_libraries,
    inputs={"spheres": In(SphereSet, "what to draw")},
    outputs={"image": Out(Image, "a picture of the spheres")},
    params={
        "seconds": Param(float, 0.0, "waits this long, the GIL released, as a renderer's threads do", units="s"),
        "meet": Param(str, "alone", "a name: the node waits until a toy_busy of the same name runs beside it"),
        "fail": Param(bool, False, "fail after waiting"),
    },
)
def toy_render(ctx, spheres, *, seconds, meet, fail):
    """Stands for a renderer (a node declared ``overlap``): it must run in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        raise RuntimeError("a node declared overlap ran outside the main thread")
    _meet(meet, "render", "busy")
    time.sleep(seconds)
    if fail:
        raise ValueError("toy render failed")
    pixels = np.zeros((4, 4, 3), np.uint8)
    pixels[..., 0] = min(255, len(spheres))
    return Image(pixels)


BUSY_LOADED: list[tuple[bool, bool]] = []  # per call of toy_busy's ``libraries``: (main thread, beside running)


def _load_busy_libraries() -> None:
    """toy_busy's ``libraries`` (as the export's USD): loaded in the main thread before the thread beside starts."""
    BUSY_LOADED.append(
        (
            threading.current_thread() is threading.main_thread(),
            any(t.name == "nodegraph-beside" for t in threading.enumerate()),
        )
    )


@loads_libraries(_load_busy_libraries)
@node(
    "toy_busy",
    inputs={"spheres": In(SphereSet, "passed through")},
    outputs={"spheres": Out(SphereSet, "same, scaled")},
    params={
        "seconds": Param(float, 0.0, "computes (holds a core) this long", units="s"),
        "meet": Param(str, "alone", "a name: the node waits until a toy_render of the same name runs beside it"),
    },
)
def toy_busy(ctx, spheres, *, seconds, meet):
    """Keeps a core busy in Python, then passes the spheres on, scaled."""
    _meet(meet, "busy", "render")
    end = time.thread_time() + seconds
    while time.thread_time() < end:
        pass
    return SphereSet(spheres.centers * 2.0, spheres.radii.copy())


@node(
    "toy_spin",
    inputs={"spheres": In(SphereSet, "passed through")},
    outputs={"spheres": Out(SphereSet, "same")},
    params={
        "steps": Param(int, 1, "iterations of a numba loop that holds the GIL (1e11: minutes)", range=(1, 10**12)),
        "started": Param(str, "", "a folder: the node writes a file named by its process id there, the loop compiled"),
    },
)
def toy_spin(ctx, spheres, *, steps, started):
    """Stands for a long numba kernel (the placement's neighbour search): deaf to signals while it runs."""
    import math

    import numba

    @numba.njit
    def spin(n):
        total = 0.0
        for i in range(n):
            total += math.sin(i)
        return total

    spin(1)  # compiled: from the file on, the loop itself runs
    if started:
        Path(started).mkdir(parents=True, exist_ok=True)
        (Path(started) / str(os.getpid())).touch()
    spin(steps)
    return SphereSet(spheres.centers.copy(), spheres.radii.copy())
