"""CDRF kernels — SPEC §4 eq. 7–9: closed form vs quadrature vs table, σ₀(water), curvature."""

import numpy as np
import pytest

from nodes.shading.cdrf import CdrfTable, cdrf_exact, cdrf_quadrature, curvature_sigma, sigma0_from_water


def test_closed_form_matches_the_convolution_integral():
    theta = np.linspace(0, np.pi, 37)[:, None]
    sigma = np.array([0.1, 0.3, 1.0, 2.5])[None, :]
    assert np.max(np.abs(cdrf_exact(theta, sigma) - cdrf_quadrature(theta, sigma, 128))) < 1e-7


def test_zero_width_is_lambert_and_light_bleeds_past_the_terminator_with_width():
    theta = np.linspace(0, np.pi, 19)
    assert np.allclose(cdrf_exact(theta, 0.0), np.maximum(np.cos(theta), 0))
    past = np.array([cdrf_exact(np.pi / 2 + 0.3, s) for s in (0.1, 0.4, 1.0)])
    assert past[0] < past[1] < past[2] and past[0] > 0


def test_table_approximation_error_shrinks_with_size():
    rng = np.random.default_rng(1)
    theta, sigma = rng.uniform(0, np.pi, 5000), rng.uniform(0, 3, 5000)
    exact = cdrf_exact(theta, sigma)
    errors = [np.max(np.abs(CdrfTable.build(n, n // 2)(theta, sigma) - exact)) for n in (16, 64, 256)]
    assert errors[0] > errors[1] > errors[2] and errors[2] < 2e-3


def test_sigma0_is_a_log_log_line_through_its_end_points():
    assert sigma0_from_water(0, 0.1, 1.0) == pytest.approx(0.1)
    assert sigma0_from_water(24, 0.1, 1.0) == pytest.approx(1.0)
    mid = [np.log(sigma0_from_water(w, 0.1, 1.0)) for w in (4, 9, 14)]
    logs = np.log(1 + np.array([4, 9, 14]))
    assert np.allclose(np.diff(mid) / np.diff(logs), np.log(10) / np.log(25))


@pytest.mark.parametrize("water", [-0.1, 24.5, 40])
def test_water_outside_the_fitted_range_is_refused(water):
    with pytest.raises(ValueError, match="water_content"):
        sigma0_from_water(water, 0.1, 1.0)


def test_sigma_is_clamped_and_symmetric_in_curvature():
    s = curvature_sigma(np.array([-2.0, 2.0, 1e6]), 0.5)
    assert s[0] == s[1] == 1.0 and s[2] == 3.0


def test_mean_curvature_of_a_sphere():
    import trimesh

    from nodes.shading.curvature import mean_curvature

    sphere = trimesh.creation.icosphere(4, radius=2.0)
    h = mean_curvature(sphere.vertices, sphere.faces)
    assert np.allclose(h, 0.5, rtol=0.01)
    inside_out = mean_curvature(sphere.vertices, sphere.faces[:, ::-1])
    assert np.allclose(inside_out, -0.5, rtol=0.01)  # normals flip, so does the sign


def test_normals_and_curvature_match_libigl_on_a_bumpy_mesh_with_obtuse_and_degenerate_faces():
    """The one-pass kernel against libigl's cotmatrix, Voronoi massmatrix and area-weighted normals (what the
    shade node used before): a randomly displaced sphere (obtuse triangles), two meshes in one array, one
    collapsed face (no area: adds nothing) and an unused vertex (normal 0, curvature 0)."""
    import igl
    import trimesh

    from nodes.shading.curvature import normals_and_curvature

    rng = np.random.default_rng(1)
    sphere = trimesh.creation.icosphere(3, radius=2.0)
    bumpy = sphere.vertices * rng.uniform(0.8, 1.2, (len(sphere.vertices), 1))
    vertices = np.concatenate([bumpy, bumpy + [5.0, 0.0, 0.0], [[9.0, 9.0, 9.0]]])
    faces = np.concatenate([sphere.faces, sphere.faces + len(bumpy)])
    degenerate = np.concatenate([faces, [[0, 0, 1]]])
    normals, curvature = normals_and_curvature(vertices, degenerate)

    used = slice(0, -1)  # libigl sizes its matrices by the faces: without the unused vertex
    expected_normals = igl.per_vertex_normals(vertices[used], faces, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA)
    laplacian = igl.cotmatrix(vertices[used], faces)
    mass = igl.massmatrix(vertices[used], faces, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    hn = -0.5 * (laplacian @ vertices[used]) / mass[:, None]
    expected = np.einsum("ij,ij->i", hn, expected_normals)
    assert np.allclose(normals[used], expected_normals, atol=1e-12)
    assert np.allclose(curvature[used], expected, rtol=1e-9, atol=1e-9)
    assert (np.ptp(curvature[used]) > 1.0) and np.all(normals[-1] == 0) and curvature[-1] == 0


def test_translucency_is_the_cdrf_share_past_the_terminator():
    """σ → 0 is Lambert (no light from past the terminator); wider kernels bring more, below an even split."""
    from nodes.shading.cdrf import SIGMA_MAX, translucency

    sigma = np.linspace(0.0, SIGMA_MAX, 50)
    t = translucency(sigma)
    assert t[0] == pytest.approx(0.0, abs=1e-9)
    assert (np.diff(t) > 0).all() and 0.5 < t[-1] <= 1.0
