"""Diffuse lighting from 9 spherical-harmonic coefficients (Ramamoorthi & Hanrahan, SIGGRAPH 2001).

The environment's radiance is projected on the real SH basis up to l = 2,
L_lm = ∫ L(ω) Y_lm(ω) dω, and the irradiance at normal n is E(n) = Σ Â_l L_lm Y_lm(n) with the
clamped-cosine kernel Â_0 = π, Â_1 = 2π/3, Â_2 = π/4 (their eqs 7–8). The renderers use the
*normalised* diffuse map D(n) = E(n)/π — the same normalisation as a Phong-exponent-1 lobe,
(1+1)/(2π)·cos θ — so a constant environment of radiance c gives D = c (thesis eq 2.5.3's DiffuseMap).
"""

from __future__ import annotations

import numpy as np

from station.model.fresnel import ClearCoat
from station.render.cubemap import equirect_directions, equirect_solid_angles

SH_BAND_GAIN = np.array(
    [
        np.pi,
        2 * np.pi / 3,
        2 * np.pi / 3,
        2 * np.pi / 3,
        np.pi / 4,
        np.pi / 4,
        np.pi / 4,
        np.pi / 4,
        np.pi / 4,
    ]
)


def sh_basis(dirs: np.ndarray) -> np.ndarray:
    """Real SH basis Y_00, Y_1−1, Y_10, Y_11, Y_2−2, Y_2−1, Y_20, Y_21, Y_22 at unit dirs (..., 3) → (..., 9)."""
    x, y, z = dirs[..., 0], dirs[..., 1], dirs[..., 2]
    return np.stack(
        [
            np.full_like(x, 0.282095),
            0.488603 * y,
            0.488603 * z,
            0.488603 * x,
            1.092548 * x * y,
            1.092548 * y * z,
            0.315392 * (3 * z * z - 1),
            1.092548 * x * z,
            0.546274 * (x * x - y * y),
        ],
        axis=-1,
    )


def sh_project(equirect: np.ndarray) -> np.ndarray:
    """SH coefficients (9, 3) of an equirectangular radiance image (H, W, 3) by exact-area quadrature."""
    h, w = equirect.shape[:2]
    basis = sh_basis(equirect_directions(h, w)) * equirect_solid_angles(h, w)[..., None]
    return np.einsum("hwk,hwc->kc", basis, equirect.astype(np.float64))


def coat_band_gain(coat: ClearCoat) -> np.ndarray:
    """Band gains (9,) of the coat-transmitted diffuse kernel t(μ) μ₊ (``ClearCoat.entry_scale``): by the
    Funk–Hecke theorem Â_l = 2π ∫₀¹ t(μ) μ P_l(μ) dμ (Gauss–Legendre, 256 nodes); Â_0 = π exactly, as
    t's cosine-weighted mean is 1. The SH twin of ``station.render.prefilter.coat_diffuse_map``."""
    x, w = np.polynomial.legendre.leggauss(256)
    mu = 0.5 * (x + 1.0)
    k = 0.5 * w * 2.0 * np.pi * coat.entry_scale(mu) * mu
    bands = [np.sum(k), np.sum(k * mu), np.sum(k * 0.5 * (3.0 * mu * mu - 1.0))]
    return np.array([bands[0]] + [bands[1]] * 3 + [bands[2]] * 5)


def sh_diffuse(coeffs: np.ndarray, normals: np.ndarray, coat: ClearCoat | None = None) -> np.ndarray:
    """Normalised diffuse map D(n) = E(n)/π (..., 3) at unit normals (..., 3) from coefficients (9, 3);
    with *coat* the coat-transmitted map D_coat (:func:`coat_band_gain`)."""
    gain = SH_BAND_GAIN if coat is None else coat_band_gain(coat)
    return sh_basis(normals) @ (coeffs * gain[:, None] / np.pi)


def sh_diffuse_matrix(coeffs: np.ndarray, coat: ClearCoat | None = None) -> np.ndarray:
    """Coefficients pre-multiplied by Â_l/π, (9, 3): what the GLSL shader evaluates against sh_basis
    (*coat*: the coat-transmitted kernel's gains, :func:`coat_band_gain`)."""
    gain = SH_BAND_GAIN if coat is None else coat_band_gain(coat)
    return (coeffs * gain[:, None] / np.pi).astype(np.float32)
