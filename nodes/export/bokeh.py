"""The thin lens's blur of the glints' pass, as a scatter of a sharp (pinhole) render — SPEC §4 preview.

Through a thin lens of aperture radius A focused at depth f, a point at depth z reaches the film as a uniform disc
of radius A |1 − f/z| / (f tan(fov_x / 2)) × width / 2 pixels (its circle of confusion: Mitsuba's ``thinlens``
samples the aperture uniformly over a disc), centred where a pinhole at the lens's centre sees the point. So the
glints' pass is rendered through a pinhole (sharp: two samples a pixel anti-alias a glint a pixel or two across)
with each pixel's depth, and each glint pixel is spread over its own circle of confusion here: what the thin lens
converges to with many samples, where two samples a pixel through the lens left a few bright dots of each
out-of-focus glint's disc (docs/look.md, "Bokeh, not dots").

Occlusion: a pinhole sees a glint or not; the lens sees it from every point of its aperture, so a nearer object
covers part of a farther glint's disc. Here a target pixel nearer than the glint's takes the share
1 − r_target / r_glint of that glint's light away (none when it is as blurred as the glint or more): an in-focus
object (r_target ≈ 0) in front cuts a blurred glint's disc sharply at its silhouette, as the lens does, and a
neighbour at about the glint's own depth (a far egg beside a far egg, the glint's own surface) barely dims it. What
a post-blur cannot give: a glint hidden from the lens's centre but seen past an edge from the aperture's rim (the
pinhole pass has no sample of it), and the partial cover of a blurred nearer object (its share is a guess).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def scatter_discs(glints, depth, radius):
    """Each pixel's glints (float32 (h, w, 3)) spread over a disc of ``radius`` pixels (its circle of confusion at
    ``depth``; (h, w) each, depth ≤ 0: nothing there, as far as can be) with anti-aliased edges: weight
    clip(r + ½ − d, 0, 1) at distance d from its centre, normalised to sum 1 over the whole disc (a disc cut by the
    film's edge or by nearer objects loses that light, as on the lens's film). A target nearer than the source keeps
    only the share min(1, r_target / r_source) of it (see the module note). r < ½: the pixel as it is. Sequential:
    the same sums in the same order, so the same bits."""
    h, w = depth.shape
    out = np.zeros((h, w, 3), np.float32)
    for y in range(h):
        for x in range(w):
            r0, g0, b0 = glints[y, x, 0], glints[y, x, 1], glints[y, x, 2]
            if r0 <= 0.0 and g0 <= 0.0 and b0 <= 0.0:
                continue
            r = radius[y, x]
            if r < 0.5:
                out[y, x, 0] += r0
                out[y, x, 1] += g0
                out[y, x, 2] += b0
                continue
            z = depth[y, x]
            reach = int(np.ceil(r + 0.5))
            total = 0.0
            for dy in range(-reach, reach + 1):
                for dx in range(-reach, reach + 1):
                    total += min(max(r + 0.5 - np.sqrt(dx * dx + dy * dy), 0.0), 1.0)
            for dy in range(-reach, reach + 1):
                ty = y + dy
                if ty < 0 or ty >= h:
                    continue
                for dx in range(-reach, reach + 1):
                    tx = x + dx
                    if tx < 0 or tx >= w:
                        continue
                    weight = min(max(r + 0.5 - np.sqrt(dx * dx + dy * dy), 0.0), 1.0)
                    if weight <= 0.0:
                        continue
                    zt = depth[ty, tx]
                    if 0.0 < zt < z:  # nearer: covers the share of the disc that it is sharper by
                        weight *= min(radius[ty, tx] / r, 1.0)
                    weight /= total
                    out[ty, tx, 0] += np.float32(r0 * weight)
                    out[ty, tx, 1] += np.float32(g0 * weight)
                    out[ty, tx, 2] += np.float32(b0 * weight)
    return out
