"""Fresnel's equations written out for the renderer's coat tests (independent of station.model.fresnel):
the unpolarised reflectance of a dielectric by Snell's law and the s and p amplitude ratios, and
1 − F_dr,ext by the trapezoid rule."""

from __future__ import annotations

import numpy as np


def fresnel(cos_i: np.ndarray, n: float) -> np.ndarray:
    """Unpolarised reflectance of a dielectric of index *n* from air at incidence cosines *cos_i*: Snell's
    law for the refracted angle, then the s and p amplitude ratios (head-on and grazing by their limits)."""
    ti = np.arccos(np.clip(cos_i, 0.0, 1.0))
    tt = np.arcsin(np.sin(ti) / n)
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = np.sin(ti - tt) / np.sin(ti + tt)
        rp = np.tan(ti - tt) / np.tan(ti + tt)
    head_on = ((n - 1.0) / (n + 1.0)) ** 2
    return np.where(ti < 1e-9, head_on, np.where(np.isclose(ti, 0.5 * np.pi), 1.0, 0.5 * (rs**2 + rp**2)))


def diffuse_transmission(n: float) -> float:
    """1 − F_dr,ext = 1 − 2 ∫₀¹ F(μ) μ dμ, trapezoid rule on 20001 points."""
    mu = np.linspace(0.0, 1.0, 20001)
    y = 2.0 * fresnel(mu, n) * mu
    return 1.0 - float(np.sum((y[1:] + y[:-1]) * 0.5 * np.diff(mu)))


def entry_weight(cos_l: float, n: float) -> float:
    """The coat's entry weight (1 − F(N·l))/(1 − F_dr,ext) by hand."""
    return float((1.0 - fresnel(np.array(cos_l), n)) / diffuse_transmission(n))
