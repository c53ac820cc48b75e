"""A procedural food-photography studio for the preview: softbox key, fill, rim light, seamless backdrop, lens.

No HDRI can be downloaded, so the light is built as a food photographer sets it (SPEC §4 preview):

- **key**: a large rectangular softbox along the shade node's key-light direction, ``KEY_DISTANCE`` subject radii
  away and ``KEY_ANGLE`` wide (half-angle): soft shadows, a window-shaped reflection on glossy skins, and a gentle
  fall-off across the dish (the near side a little brighter);
- **fill**: a larger, dimmer panel low on the camera's side, mirrored from the key about the camera's azimuth
  (a bounce card): the shadow side keeps detail, at ``FILL_IRRADIANCE`` / ``KEY_IRRADIANCE`` ≈ 1 : 4 (two stops);
- **rim**: a strip light behind the subject, opposite the camera and above it: backlight makes glossy eggs and
  wet rice glisten at their edges and lifts the subject off the backdrop;
- **backdrop**: a matte seamless sweep (floor curving up into a wall behind the subject, away from the camera),
  so there is no horizon line at any elevation; a dim uniform ambient (``AMBIENT``) stands for the studio's walls;
- **lens**: a thin lens focused on the front of the subject (``focus``: a quantile of the subject's depths seen
  from the camera) at the f-number ``f_stop`` of a full-frame camera with the preview's field of view (36 mm
  film width), in the scene's real millimetres: the back of the dish softens as in a close-up food photograph.

Irradiances (perpendicular, at the subject's centre) set each light's radiance by its projected solid angle
(``projected_solid_angle``); each light is sampled in proportion to its irradiance (Mitsuba ``sampling_weight``).
The values are chosen, not measured: the classic food set-up (key from the side and above, fill two stops under,
backlight), at an exposure that puts lit white rice near the tone curve's knee as before.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

AMBIENT = 0.06  # radiance of the uniform ambient (the studio's walls; was a 0.4 sky that lit everything evenly)
KEY_IRRADIANCE = 1.9  # perpendicular irradiance of the key at the subject's centre
KEY_DISTANCE = 8.0  # subject radii from the subject's centre to the softbox
KEY_ANGLE = 0.35  # rad, half-angle of the softbox seen from the subject (its long side; the short side ¾ of it)
FILL_IRRADIANCE = 0.45  # two stops under the key
FILL_ELEVATION = 15.0  # degrees above the horizon: a bounce card low on the camera's side
FILL_ANGLE = 0.5  # rad, half-angle: larger and softer than the key
RIM_IRRADIANCE = 1.2  # the backlight, opposite the camera
RIM_ELEVATION = 35.0  # degrees above the horizon
RIM_ANGLES = (0.45, 0.08)  # rad, half-angles of the strip: wide across, narrow in height
BACKDROP_COLOR = (0.50, 0.45, 0.39)  # linear RGB of the matte sweep: a warm greige paper
BACKDROP_BEHIND = 4.0  # subject radii from the subject's centre (away from the camera) to where the sweep rises
BACKDROP_COVE = 4.0  # subject radii: the radius of the sweep's curve
BACKDROP_EXTENT = 30.0  # subject radii: the sweep's half-width, its depth in front and its height
FILM_WIDTH = 36.0  # mm, full-frame: the focal length that gives the preview's field of view
SETTINGS = ("sweep", "table")  # what the subject stands on (the preview's ``setting``)
# the table (``setting`` 'table'): oiled oak boards. Oak heartwood measures L* ≈ 55–70, a* ≈ 5–9, b* ≈ 18–25 in
# CIELAB (Hălălișan et al. 2023, "Wood colour variations of Quercus species in Romania", Forests 14:230: seven oak
# species, differing mostly in L* and b*), and a clear coat or oil darkens wood and deepens its latewood (Tashiro
# and Nakamura, "Characterization of colors distributed on lumber surface by imaging spectroscopy", J. Soc. Mat.
# Sci. Japan 62(4)): an oiled board here averages L* 50, a* 9, b* 24 = linear (0.29, 0.16, 0.077). Its latewood
# bands are TABLE_LATEWOOD of that and its earlywood TABLE_EARLYWOOD: ΔL* ≈ 6 between them, within the spread one
# species shows (the figure above), so the grain reads at arm's length and not as stripes; each board differs by
# ± TABLE_BOARD_SPREAD in brightness. Oak's rings are 1–4 mm a year: each ring's width is drawn around TABLE_RING
# with TABLE_RING_SPREAD (a log-normal share), so no two bands repeat
TABLE_COLOR = (0.29, 0.16, 0.077)
TABLE_LATEWOOD = 0.84
TABLE_EARLYWOOD = 1.06
TABLE_BOARD_SPREAD = 0.08
TABLE_RING_SPREAD = 0.45
TABLE_BOARD = 110.0  # mm: a board's width (oak table tops and floor boards: 90–140 mm)
TABLE_RING = 2.5  # mm: the mean spacing of the growth rings seen on a flat-sawn face (oak: 1–4 mm a year)
TABLE_TILE = 440.0  # mm: the texture's side (4 boards), repeated over the table
TABLE_PIXELS = 2048  # the texture's side: 0.21 mm a pixel
TABLE_EXTENT = 30.0  # subject radii: the table top's half-side (it fills the frame behind the subject)
TABLE_ROUGHNESS = 0.45  # an oiled, not varnished, face: a broad sheen, no mirror


@dataclass(frozen=True)
class Light:
    """A rectangular area light facing the subject's centre: where it is, its half sizes and its radiance."""

    center: np.ndarray
    half_sizes: tuple[float, float]
    radiance: float
    irradiance: float


def projected_solid_angle(half_width: float, half_height: float, distance: float) -> float:
    """Projected solid angle (sr) of a rectangle seen face-on from a point on its axis, ∫cos θ dω: the irradiance
    it gives per unit radiance (the point-to-parallel-rectangle form factor × π, four quadrants)."""
    a, b = half_width / distance, half_height / distance
    ra, rb = np.sqrt(1 + a * a), np.sqrt(1 + b * b)
    return float(2.0 * (a / ra * np.arctan(b / ra) + b / rb * np.arctan(a / rb)))


def _direction(azimuth_vector: np.ndarray, elevation: float) -> np.ndarray:
    el = np.radians(elevation)
    return np.cos(el) * azimuth_vector + np.sin(el) * np.array([0.0, 0.0, 1.0])


def _light(target, radius, direction, distance, half_angles, irradiance) -> Light:
    direction = np.asarray(direction, np.float64) / np.linalg.norm(direction)
    d = distance * radius
    half = (float(d * np.tan(half_angles[0])), float(d * np.tan(half_angles[1])))
    radiance = irradiance / projected_solid_angle(half[0], half[1], d)
    return Light(target + d * direction, half, float(radiance), float(irradiance))


def camera_side(view: np.ndarray) -> np.ndarray:
    """Unit horizontal vector from the subject towards the camera (any, if the camera looks straight down)."""
    h = np.array([view[0], view[1], 0.0])
    return h / np.linalg.norm(h) if np.linalg.norm(h) > 1e-6 else np.array([0.0, -1.0, 0.0])


LIGHTS = ("key", "fill", "rim")  # the studio's softboxes (``lights``), by name in the scene description


def lights(
    target: np.ndarray, radius: float, view: np.ndarray, key_direction, key_gain: float = 1.0
) -> dict[str, Light]:
    """Key, fill and rim around a subject of ``radius`` centred at ``target``; ``view`` points towards the camera,
    ``key_direction`` towards the key (the shade node's key light); ``key_gain`` scales the key's irradiance (the
    shade node's key intensity over its default, ``ShadedScene.key_gain``)."""
    key = np.asarray(key_direction, np.float64) / np.linalg.norm(key_direction)
    front = camera_side(view)
    key_h = np.array([key[0], key[1], 0.0])
    key_h = key_h / np.linalg.norm(key_h) if np.linalg.norm(key_h) > 1e-6 else front
    fill_h = 2.0 * float(key_h @ front) * front - key_h  # the key mirrored about the camera's azimuth
    fill_h = fill_h / np.linalg.norm(fill_h)
    key_angles = (KEY_ANGLE, 0.75 * KEY_ANGLE)
    return {
        "key": _light(target, radius, key, KEY_DISTANCE, key_angles, key_gain * KEY_IRRADIANCE),
        "fill": _light(
            target, radius, _direction(fill_h, FILL_ELEVATION), KEY_DISTANCE, (FILL_ANGLE,) * 2, FILL_IRRADIANCE
        ),
        "rim": _light(
            target, radius, _direction(-front, RIM_ELEVATION), 0.5 * KEY_DISTANCE, RIM_ANGLES, RIM_IRRADIANCE
        ),
    }


def light_dict(light: Light, target: np.ndarray) -> dict:
    """Mitsuba rectangle with an area emitter, its emitting side (+z) turned to ``target``."""
    import mitsuba as mi

    forward = target - light.center
    up = [0.0, 0.0, 1.0] if abs(forward[2]) < 0.99 * np.linalg.norm(forward) else [0.0, 1.0, 0.0]
    frame = mi.ScalarTransform4f().look_at(origin=light.center.tolist(), target=target.tolist(), up=up)
    return {
        "type": "rectangle",
        "to_world": frame @ mi.ScalarTransform4f().scale([light.half_sizes[0], light.half_sizes[1], 1.0]),
        "emitter": {
            "type": "area",
            "radiance": {"type": "rgb", "value": light.radiance},
            "sampling_weight": light.irradiance,
        },
    }


def backdrop_mesh(target: np.ndarray, radius: float, floor: float, view: np.ndarray, segments: int = 16):
    """(vertices, faces, normals) of the seamless sweep: a floor at height ``floor`` from in front of the subject
    to ``BACKDROP_BEHIND`` radii behind it (seen from the camera), a quarter circle of ``BACKDROP_COVE`` radii up,
    then a wall; faces wound so that their normals face the subject."""
    front = camera_side(view)
    across = np.array([-front[1], front[0], 0.0])
    behind, cove, extent = BACKDROP_BEHIND * radius, BACKDROP_COVE * radius, BACKDROP_EXTENT * radius
    phi = np.linspace(0.0, np.pi / 2, segments + 1)
    # profile (w: distance behind the subject's centre, z: height over the floor) and its inward normal
    w = np.concatenate([[-extent], behind + cove * np.sin(phi), [behind + cove]])
    z = np.concatenate([[0.0], cove * (1.0 - np.cos(phi)), [extent]])
    nw = np.concatenate([[0.0], -np.sin(phi), [-1.0]])
    nz = np.concatenate([[1.0], np.cos(phi), [0.0]])
    base = np.array([target[0], target[1], floor])
    rows = []
    normals = []
    for side in (-extent, extent):
        rows.append(base + side * across + np.outer(w, -front) + np.outer(z, [0.0, 0.0, 1.0]))
        normals.append(np.outer(nw, -front) + np.outer(nz, [0.0, 0.0, 1.0]))
    vertices = np.concatenate(rows)
    n = len(w)
    k = np.arange(n - 1)
    quads = np.stack([k, k + 1, n + k + 1, n + k], axis=1)
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    # wind each face so that its geometric normal agrees with the profile's normal
    tri = vertices[faces]
    geometric = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    wanted = np.concatenate(normals)[faces].mean(axis=1)
    flip = np.einsum("ij,ij->i", geometric, wanted) < 0
    faces[flip] = faces[flip][:, ::-1]
    return vertices, faces.astype(np.int64), np.concatenate(normals)


def backdrop_dict(path: Path, target: np.ndarray, radius: float, floor: float, view: np.ndarray) -> dict:
    """The sweep as a PLY shape written to ``path``, matte ``BACKDROP_COLOR``."""
    from .mesh_files import write_ply

    vertices, faces, normals = backdrop_mesh(target, radius, floor, view)
    colors = np.tile(BACKDROP_COLOR, (len(vertices), 1))
    write_ply(path, vertices, faces, normals, colors)
    return {
        "type": "ply",
        "filename": str(path),
        "face_normals": True,
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(BACKDROP_COLOR)}},
    }


def focal_length(fov: float) -> float:
    """mm: the focal length of a full-frame (36 mm wide) camera with horizontal field of view ``fov`` (degrees)."""
    return FILM_WIDTH / 2 / float(np.tan(np.radians(fov) / 2))


def aperture_radius(fov: float, f_stop: float) -> float:
    """Radius (mm) of the thin lens's aperture: focal length / (2 × f-number); 0 for a pinhole (``f_stop`` 0)."""
    return 0.0 if f_stop <= 0 else focal_length(fov) / (2.0 * f_stop)


def blur_radius(depth, aperture: float, focus: float, tan_x: float, width: int):
    """Pixels: the radius of a thin lens's circle of confusion for points at ``depth`` along the optical axis
    (aperture radius ``aperture``, in focus at ``focus``, half the horizontal field's tangent ``tan_x``, a film
    ``width`` pixels wide): A |1 − f/z| / (f tan(fov_x / 2)) × width / 2."""
    return aperture * np.abs(1.0 - focus / np.asarray(depth)) / (focus * tan_x) * (width / 2)


def focus_distance(points: np.ndarray, origin: np.ndarray, target: np.ndarray, focus: float) -> float:
    """Distance along the optical axis from the camera to the plane in focus: the ``focus`` quantile of the
    subject's depths (0 its nearest point, 1 its farthest)."""
    forward = (target - origin) / np.linalg.norm(target - origin)
    return float(np.quantile((np.asarray(points) - origin) @ forward, focus))


@functools.cache
@functools.cache
def wood_texture(pixels: int = TABLE_PIXELS) -> np.ndarray:
    """The table's boards as a (pixels, pixels, 3) float32 linear-RGB tile of ``TABLE_TILE`` mm, repeating on both
    axes: ``TABLE_TILE / TABLE_BOARD`` boards side by side along x (a thin dark joint between), each a flat-sawn
    face whose growth rings run along y, wavering, each ring its own width (``TABLE_RING``, ``TABLE_RING_SPREAD``),
    latewood a little darker than earlywood (``TABLE_LATEWOOD``, ``TABLE_EARLYWOOD``), with the fine open pores of
    oak as short dark streaks along the grain. Fixed (its own seed): the same table for every scene, made once a
    process (read-only)."""
    rng = np.random.default_rng(20261206)
    boards = max(1, int(round(TABLE_TILE / TABLE_BOARD)))
    mm = TABLE_TILE / pixels
    x = (np.arange(pixels) + 0.5) * mm
    y = x.copy()
    width = TABLE_TILE / boards
    board = np.minimum((x // width).astype(np.int64), boards - 1)
    across = x - board * width  # mm from the board's left edge
    out = np.empty((pixels, pixels, 3), np.float32)
    periods = np.arange(1, 6)  # the waver repeats with the tile: whole periods along y
    for b in range(boards):
        columns = board == b
        u = across[columns][None, :]
        centre = rng.uniform(-0.6, 1.6) * width  # the pith, off the face: the rings cross it as arcs
        depth = rng.uniform(20.0, 60.0)  # mm from the face to the pith
        phase = rng.uniform(0, 2 * np.pi, len(periods))
        amplitude = rng.uniform(0.5, 2.0, len(periods)) / periods
        waver = (amplitude[:, None] * np.sin(2 * np.pi * periods[:, None] * y / TABLE_TILE + phase[:, None])).sum(0)
        radius = np.sqrt((u - centre - waver[:, None]) ** 2 + depth**2)
        # the rings' outer radii: each its own width, so a radius's place in its ring is found by interpolation
        widths = TABLE_RING * rng.lognormal(-0.5 * TABLE_RING_SPREAD**2, TABLE_RING_SPREAD, 400)
        edges = np.concatenate([[0.0], np.cumsum(widths)])
        place = np.interp(radius, edges, np.arange(len(edges)))  # ring number + the share of the ring crossed
        within = place - np.floor(place)
        late = np.clip((within - 0.7) / 0.3, 0.0, 1.0) ** 1.5  # latewood: the ring's outer 30 %, darkening outwards
        shade = TABLE_EARLYWOOD + (TABLE_LATEWOOD - TABLE_EARLYWOOD) * late
        shade = shade * (1.0 + TABLE_BOARD_SPREAD * rng.uniform(-1, 1))
        # oak's open pores: short dark streaks along the grain, 2–12 mm long, scattered across the face
        n_cols = int(columns.sum())
        pores = np.ones((pixels, n_cols), np.float32)
        count = int(n_cols * pixels * mm * mm / 6.0)  # about one a 6 mm²
        cx = rng.integers(0, n_cols, count)
        cy = rng.integers(0, pixels, count)
        length = (rng.uniform(2.0, 12.0, count) / mm).astype(np.int64)
        depth_of = rng.uniform(0.80, 0.93, count).astype(np.float32)
        starts = np.repeat(np.cumsum(length) - length, length)  # each streak's pixels, rows along y from cy
        rows = (np.repeat(cy, length) + np.arange(int(length.sum())) - starts) % pixels
        np.minimum.at(pores, (rows, np.repeat(cx, length)), np.repeat(depth_of, length))  # crossings: the darker
        out[:, columns] = (shade * pores)[..., None] * np.asarray(TABLE_COLOR, np.float32)
    seam = np.minimum(across, width - across) < 0.4  # the joint between boards, 0.8 mm, in shadow
    out[:, seam] *= 0.45
    out = np.clip(out, 0.0, 1.0)
    out.flags.writeable = False
    return out


def wood_png(path: Path) -> Path:
    """``wood_texture`` written as an 8-bit sRGB PNG at ``path`` (for Mitsuba's and Blender's image textures), at
    the outputs' zlib level: the same pixels as the default level's, for ≈ a fifth of the encoding time."""
    from PIL import Image as PILImage

    from nodegraph.output_files import PNG_LEVEL

    from .mesh_files import linear_to_srgb8

    PILImage.fromarray(linear_to_srgb8(wood_texture())).save(path, compress_level=PNG_LEVEL)
    return path


def table_corners(target: np.ndarray, radius: float, floor: float, view: np.ndarray) -> np.ndarray:
    """The table top's four corners (counter-clockwise seen from above), ``TABLE_EXTENT`` radii from the subject's
    centre at height ``floor``, its boards running away from the camera (their texture's y along the view)."""
    front = camera_side(view)
    across = np.array([-front[1], front[0], 0.0])
    half = TABLE_EXTENT * radius
    centre = np.array([target[0], target[1], floor])
    signs = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    return np.array([centre + half * (a * across + b * front) for a, b in signs])


def table_uv(radius: float) -> np.ndarray:
    """Texture coordinates of ``table_corners``: the tile repeats every ``TABLE_TILE`` mm."""
    repeats = 2 * TABLE_EXTENT * radius / TABLE_TILE
    return np.array([[0.0, 0.0], [repeats, 0.0], [repeats, repeats], [0.0, repeats]])


def table_dict(folder: Path, target: np.ndarray, radius: float, floor: float, view: np.ndarray) -> dict:
    """The table top: a Mitsuba rectangle under the subject with the boards' texture (``wood_png``, written into
    ``folder``), oiled (``TABLE_ROUGHNESS``)."""
    import mitsuba as mi

    corners = table_corners(target, radius, floor, view)
    centre = corners.mean(axis=0)
    x_axis = (corners[1] - corners[0]) / 2  # the rectangle's local x: across the view
    y_axis = (corners[3] - corners[0]) / 2  # its local y: away from the camera
    frame = np.eye(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = x_axis, y_axis, [0.0, 0.0, 1.0], centre
    repeats = float(table_uv(radius)[2, 0])
    texture = {
        "type": "bitmap",
        "filename": str(wood_png(folder / "table.png")),
        "wrap_mode": "repeat",
        "to_uv": mi.ScalarTransform4f().scale([repeats, repeats, 1.0]),
    }
    return {
        "type": "rectangle",
        "to_world": mi.ScalarTransform4f(frame.tolist()),
        "bsdf": {"type": "principled", "base_color": texture, "roughness": TABLE_ROUGHNESS, "specular": 0.5},
    }
