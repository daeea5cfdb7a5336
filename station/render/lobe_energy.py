"""The perceptual gloss and colour fit and the gloss lobes' energy (methods in :mod:`station.render.lobe_fit`).

``perceptual`` weighs every row's residual by the target's own magnitude to the power −2/3 (a residual
then costs in proportion to the ΔL* it causes) and solves exact NNLS per design; its gloss part carries an
energy row. :func:`conserve_gloss_energy` then makes every method's fitted gloss reflect exactly the
designed lobe's albedo ρ_s.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.render.lobes import LobeBasis

#: Exponent of the perceptual row weights (CIELAB: dL*/dY ∝ Y^(−2/3)).
PERCEPTUAL_POWER = 2.0 / 3.0
#: Floor (sr⁻¹) of the value a perceptual row weight divides by (reflectance ~0.003 at N·L = 1): keeps a
#: black design's rows finite.
PERCEPTUAL_FLOOR = 1e-3
#: Weight of the energy row of the perceptual gloss fit, relative to the norm of the weighted sample rows:
#: large enough that the row holds to ~1e-6 before :func:`conserve_gloss_energy` makes it exact.
ENERGY_ROW_WEIGHT = 1.0e3


def _solve_perceptual(
    prob: Any, t: Any, energy_row: bool = True
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Perceptually weighted exact NNLS (module docstring): (k, d, 3) colour and (d, m) gloss weights.

    *prob* a ``lobe_fit.FitProblem``, *t* its ``lobe_fit.Targets`` (typed loosely: lobe_fit imports this
    module). *energy_row*: add the gloss energy row (False: the thesis's point samples alone)."""
    from scipy.optimize import nnls

    g = prob.geometry
    rc, rg = prob.colour_rows, prob.gloss_rows
    b_c = prob.colour_b(t)  # (d, rows, 3), rows weighted by √(solid angle)
    value_c = b_c / g.weight[rc][None, :, None]  # the target BRDF·cos itself
    s_c = np.maximum(value_c, PERCEPTUAL_FLOOR) ** -PERCEPTUAL_POWER
    d, k = len(t), prob.colour.a.shape[1]
    x_c = np.zeros((k, d, 3))
    for i in range(d):
        for c in range(3):
            s = s_c[i, :, c]
            x_c[:, i, c] = nnls(prob.colour.a * s[:, None], b_c[i, :, c] * s, maxiter=50 * k)[0]
    if prob.gloss is None:
        return x_c, np.zeros((d, prob.basis.size))
    lobe_g = prob._gloss_values(t, rg)  # (d, rows) unweighted gloss term
    grey_g = t.rho[:, prob.alpha_index[rg], :].mean(axis=2) * (g.n_dot_l[rg] / np.pi)[None, :]
    s_g = np.maximum(lobe_g + grey_g, PERCEPTUAL_FLOOR) ** -PERCEPTUAL_POWER
    b_g = lobe_g * g.weight[rg][None, :]
    m = prob.gloss.a.shape[1]
    x_g = np.zeros((d, m))
    energy = lobe_energies(prob.basis)
    for i in range(d):
        a = prob.gloss.a * s_g[i][:, None]
        # the energy row Σ K_G,i 2π/(E_i+1) = ρ_s, weighted to dominate every sample row (module doc)
        lam = ENERGY_ROW_WEIGHT * np.linalg.norm(a) / np.linalg.norm(energy) * float(energy_row)
        a_e = np.vstack([a, lam * energy[None, :]])
        b_e = np.append(b_g[i] * s_g[i], lam * t.specular_albedo[i])
        x_g[i] = nnls(a_e, b_e, maxiter=50 * m)[0]
    return x_c, x_g


def lobe_energies(basis: LobeBasis) -> NDArray[np.float64]:
    """Reflected share per unit weight of each basis lobe, ∫ cos^E ψ dω = 2π/(E + 1) (sr, shape (m,))."""
    return 2.0 * np.pi / (np.asarray(basis.exponents, dtype=float) + 1.0)


def conserve_gloss_energy(
    k_g: NDArray[np.float64], basis: LobeBasis, specular_albedo: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Scale each design's gloss weights so the fitted lobes reflect exactly its lobe albedo ρ_s.

    The designed lobe ρ_s (n + 1)/(2π) cosⁿψ reflects ρ_s of the incident energy whatever n; the basis
    lobes reflect Σ K_G,i 2π/(E_i + 1) (:func:`lobe_energies`). A point-sample fit of a lobe sharper
    than the sharpest basis lobe (above about 95 GU) misses most of its peak and would reflect less as
    the gloss rises (0 for a mirror); here the fitted share is set to ρ_s (the fitted shape kept), and a
    fit with no gloss weight left puts ρ_s into the sharpest basis lobe (the mirror's best stand-in).

    Parameters
    ----------
    k_g
        (d, m) fitted gloss weights K_G,i ≥ 0 (sr⁻¹).
    basis
        The lobe basis of the fit.
    specular_albedo
        (d,) designed lobe albedo ρ_s (dimensionless, ≥ 0).

    Returns
    -------
    (d, m) weights ≥ 0 with Σ K_G,i 2π/(E_i + 1) = ρ_s for every design.
    """
    energy = lobe_energies(basis)
    rho = np.asarray(specular_albedo, dtype=float).reshape(-1)
    x = np.asarray(k_g, dtype=float).reshape(rho.size, energy.size)
    share = x @ energy
    ok = share > 1e-12 * np.maximum(rho, 1e-300)
    out = np.where(ok[:, None], x * (rho / np.where(ok, share, 1.0))[:, None], 0.0)
    sharpest = int(np.argmax(energy == energy.min()))
    out[~ok, sharpest] = rho[~ok] / energy[sharpest]
    return out
