"""The preview node — a Mitsuba 3 (scalar_rgb) path-traced PNG of the CDRF-shaded scene."""

import numpy as np
import pytest

from nodes.export import preview


def _render(scene, **over):
    return preview.call(scene=scene, **{"width": 64, "height": 48, "samples": 2, **over}).pixels


def test_preview_shows_the_shaded_scene(shaded):
    image = _render(shaded)
    assert image.shape == (48, 64, 3) and image.dtype == np.uint8
    background = image[0, 0].astype(int)
    differs = np.abs(image.astype(int) - background).sum(axis=2) > 30
    assert 0.1 < differs.mean() < 0.95  # the scene fills part of the frame, not all of it
    orange = (image[..., 0].astype(int) - image[..., 2].astype(int)) > 80
    assert orange.any()  # the ikura shows


def test_preview_is_deterministic(shaded):
    assert np.array_equal(_render(shaded), _render(shaded))


def test_zero_sun_direction_is_refused(shaded):
    with pytest.raises(ValueError, match="sun_direction"):
        _render(shaded, sun_direction=(0.0, 0.0, 0.0))
