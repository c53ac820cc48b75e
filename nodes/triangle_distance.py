"""Point–triangle offset (Ericson, Real-Time Collision Detection §5.1.5), shared by the grain
voxeliser, the medial spheres and the collider's distance grid — SPEC §1.4, §2.5, §3.

Scalar arithmetic only: small temporary arrays would be heap-allocated per call in numba, and
``a @ b`` on 3-vectors goes to BLAS (whose thread pool starved the parallel kernels, issue 6).
"""

from numba import njit


@njit(cache=True, inline="always")
def dot3(ax, ay, az, bx, by, bz):
    """a · b of two 3-vectors given as scalars."""
    return ax * bx + ay * by + az * bz


@njit(cache=True)
def point_triangle_offset(px, py, pz, a, b, c):
    """p − q for q the point of triangle abc closest to p (a, b, c: 3-vectors); its length is the
    distance, its sign against the face normal tells the side."""
    ax, ay, az = a[0], a[1], a[2]
    abx, aby, abz = b[0] - ax, b[1] - ay, b[2] - az
    acx, acy, acz = c[0] - ax, c[1] - ay, c[2] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = dot3(abx, aby, abz, apx, apy, apz)
    d2 = dot3(acx, acy, acz, apx, apy, apz)
    if d1 <= 0.0 and d2 <= 0.0:
        return apx, apy, apz
    bpx, bpy, bpz = px - b[0], py - b[1], pz - b[2]
    d3 = dot3(abx, aby, abz, bpx, bpy, bpz)
    d4 = dot3(acx, acy, acz, bpx, bpy, bpz)
    if d3 >= 0.0 and d4 <= d3:
        return bpx, bpy, bpz
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        qx, qy, qz = apx - v * abx, apy - v * aby, apz - v * abz
        return qx, qy, qz
    cpx, cpy, cpz = px - c[0], py - c[1], pz - c[2]
    d5 = dot3(abx, aby, abz, cpx, cpy, cpz)
    d6 = dot3(acx, acy, acz, cpx, cpy, cpz)
    if d6 >= 0.0 and d5 <= d6:
        return cpx, cpy, cpz
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        qx, qy, qz = apx - w * acx, apy - w * acy, apz - w * acz
        return qx, qy, qz
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        qx = bpx - w * (c[0] - b[0])
        qy = bpy - w * (c[1] - b[1])
        qz = bpz - w * (c[2] - b[2])
        return qx, qy, qz
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    qx, qy, qz = apx - abx * v - acx * w, apy - aby * v - acy * w, apz - abz * v - acz * w
    return qx, qy, qz
