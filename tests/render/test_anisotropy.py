"""Ward anisotropy by off-specular samples (eqs 2.5.4–2.5.7) against brute-force integration of eq 2.5.4."""

from __future__ import annotations

import numpy as np
import pytest

from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.render import anisotropy as an
from station.render import prefilter, procedural, shapes, tonemap
from station.render.environment import Environment
from station.render.errors import RenderInputError
from station.render.numpy_renderer import gbuffer

EXPS = (1.0, 4.0, 16.0, 64.0, 256.0, 1024.0, 4096.0)
SCENE = shapes.Scene("sphere", camera=shapes.Camera((0.0, 0.5, 5.0), (0.0, 0.0, 0.0), fov_deg=28))
LOBE = an.WardLobe((0.8, 0.8, 0.8), 0.05, 0.25)


def test_ward_albedo_under_constant_light_matches_brute_force():
    env = Environment("c", np.full((64, 128, 3), 1.0, np.float32))
    basis = prefilter.prefilter_basis(env, EXPS, engine="numpy")
    m = gbuffer(SCENE, 20, 20).mask
    truth = an.ward_truth(SCENE, env.to_cube(32), LOBE, 20, 20)[m]
    for j in (1, 9):
        got = an.render_anisotropic(SCENE, basis, LOBE, j, 20, 20)[m]
        assert np.median(np.abs(got - truth) / truth) < 0.03


def test_quality_improves_with_off_specular_samples():
    env = procedural.light_booth(128)
    basis = prefilter.prefilter_basis(env, EXPS, engine="numpy")
    w = 24
    m = gbuffer(SCENE, w, w).mask
    truth = an.ward_truth(SCENE, env.to_cube(32), LOBE, w, w)[m]

    def lab(x):
        return linear_srgb_to_lab(tonemap.srgb_decode(tonemap.to_display(x) / 255.0))

    err = {
        j: delta_e(lab(an.render_anisotropic(SCENE, basis, LOBE, j, w, w)[m]), lab(truth)).mean()
        for j in (1, 9)
    }
    assert err[9] < 0.6 * err[1]
    assert err[9] < 1.5


def test_isotropic_fit_is_nonnegative_and_bad_lobes_rejected():
    w = an.fit_isotropic(EXPS, 0.05)
    assert (w >= 0).all() and w.sum() > 0
    with pytest.raises(RenderInputError):
        an.WardLobe((1, 1, 1), 0.2, 0.1)
    with pytest.raises(RenderInputError):
        an.WardLobe((1, 1, 1), 0.0, 0.1)
