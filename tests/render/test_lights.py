"""Compact bright sources taken out of the environment and shaded exactly (wide lobes)."""

from __future__ import annotations

import numpy as np
import pytest

from station.render import numpy_renderer as nr
from station.render import prefilter, procedural, shapes
from station.render.cubemap import equirect_directions, equirect_solid_angles
from station.render.environment import Environment, extract_lights
from station.render.weights import LobeWeights


def _const_plus_sun(h: int = 128) -> tuple[np.ndarray, np.ndarray]:
    eq = np.full((h, 2 * h, 3), 0.5, np.float32)
    sun = np.array([0.3, 0.8, 0.52])
    sun /= np.linalg.norm(sun)
    d = equirect_directions(h, 2 * h)
    eq[(d @ sun) > np.cos(np.radians(2.0))] = 400.0
    return eq, sun


def test_extraction_conserves_energy_and_finds_the_sun():
    sky = procedural.sunny_sky(256, sun_elevation_deg=30, sun_azimuth_deg=60)
    residual, lights = extract_lights(sky)
    assert 1 <= lights.count <= 8
    sun = procedural.sun_direction(30, 60)
    brightest = int(np.argmax(lights.flux[:, 1]))
    assert np.degrees(np.arccos(lights.directions[brightest] @ sun)) < 1.0
    sa = equirect_solid_angles(sky.height, 256)
    total = (sky.equirect * sa[..., None]).sum(axis=(0, 1))
    split = (residual.equirect * sa[..., None]).sum(axis=(0, 1)) + lights.flux.sum(axis=0)
    assert split == pytest.approx(total, rel=1e-5)
    assert residual.equirect.max() < sky.equirect.max()


def test_no_lights_in_a_uniform_environment():
    env = Environment("c", np.full((16, 32, 3), 1.0, np.float32))
    residual, lights = extract_lights(env)
    assert lights.count == 0 and residual is env


def test_wide_lobe_with_sun_matches_brute_force_integral():
    eq, _ = _const_plus_sun()
    env = Environment("sun", eq)
    e = 8.0
    exps = (e, 500.0)
    k_dd = np.array([[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]])
    paint = LobeWeights(exps, np.zeros(3), k_dd, np.zeros(2))
    scene = shapes.Scene("sphere")
    g = nr.gbuffer(scene, 24, 24)
    m = g.mask & (g.n_dot_v > 0.2)
    dirs = equirect_directions(*eq.shape[:2]).reshape(-1, 3)
    sa = np.broadcast_to(equirect_solid_angles(*eq.shape[:2]), eq.shape[:2]).reshape(-1)
    rad = eq.reshape(-1, 3)[:, 0] * sa
    # eq 2.3.3 integrated directly: ∫ L(ω) K_DD (N·ω)₊ (R·ω)₊^E dω
    n, r = g.normal[m], g.reflect[m]
    ref = (np.clip(n @ dirs.T, 0, None) * np.clip(r @ dirs.T, 0, None) ** e) @ rad
    errs = {}
    for lights in (True, False):
        basis = prefilter.prefilter_basis(env, exps, engine="numpy", lights=lights)
        got = nr.shade_pixels(basis, paint, n, r, g.n_dot_v[m])[:, 0]
        errs[lights] = np.abs(got - ref) / ref
    assert np.median(errs[True]) < 0.02 and np.percentile(errs[True], 95) < 0.05
    assert np.median(errs[False]) > 2 * np.median(errs[True])


def test_extended_lamp_smooths_the_lobe_like_brute_force():
    """A lamp 12° in radius is no point for a lobe of exponent 30 (≈ 10° wide): its spread s² makes the
    light term the lobe of exponent E / (1 + E s²), which follows the lobe integrated over the lamp's pixels
    (brute force) several times more closely than the point light at the lamp's centre does."""
    from dataclasses import replace

    from station.render.environment import spread_exponent

    h = 256
    eq = np.full((h, 2 * h, 3), 0.01, np.float32)
    lamp = np.array([0.2, 0.9, 0.3])
    lamp /= np.linalg.norm(lamp)
    d = equirect_directions(h, 2 * h)
    inside = (d @ lamp) > np.cos(np.radians(12.0))
    eq[inside] = 50.0
    _, lights = extract_lights(Environment("lamp", eq))
    assert lights.count == 1
    # a uniform disc of angular radius a: per-axis variance a²/4
    assert np.sqrt(lights.spreads()[0]) == pytest.approx(np.radians(12.0) / 2.0, rel=0.05)
    assert spread_exponent(30.0, np.array([0.0]))[0] == 30.0
    e = 30.0
    dirs = d.reshape(-1, 3)[inside.reshape(-1)]
    sa = np.broadcast_to(equirect_solid_angles(h, 2 * h), (h, 2 * h))[inside] * 50.0
    g = nr.gbuffer(shapes.Scene("sphere"), 32, 32)
    m = g.mask & (g.n_dot_v > 0.2)
    n, r = g.normal[m], g.reflect[m]
    ref = (e + 1.0) / (2.0 * np.pi) * (np.clip(n @ dirs.T, 0, None) * np.clip(r @ dirs.T, 0, None) ** e) @ sa
    lit = ref > 0.05 * ref.max()
    basis = prefilter.prefilter_basis(Environment("lamp", eq), (e, 500.0), engine="numpy")
    assert basis.lights is not None  # the lamp is taken out as a light
    terms = nr.light_terms(basis, 0, n, r)
    assert terms is not None
    spread = terms[1][:, 0]
    point_terms = nr.light_terms(replace(basis, lights=replace(basis.lights, spread=None)), 0, n, r)
    assert point_terms is not None
    point = point_terms[1][:, 0]
    err_spread = np.abs(spread - ref)[lit].mean() / ref[lit].mean()
    err_point = np.abs(point - ref)[lit].mean() / ref[lit].mean()
    assert err_spread < 0.1 and err_spread < err_point / 3.0, (err_spread, err_point)
