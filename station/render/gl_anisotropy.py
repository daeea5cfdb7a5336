"""The anisotropic lobe of :class:`station.render.gl_renderer.GLRenderer` (eqs 2.5.4–2.5.7): its albedo
table texture and isotropic fit per (α_x, α_y), the level of detail's sample count, and the frame's
uniforms (``shaders/anisotropy.glsl``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from station.model.anisotropy import Anisotropy
from station.render import anisotropy as an
from station.render import gl_textures as tx
from station.render.errors import RenderInputError

if TYPE_CHECKING:
    from station.render.lod import AnisotropyChoice


def anisotropy_frame(
    ctx: Any,
    basis: Any,
    order: np.ndarray,
    cache: dict[tuple, tuple],
    pair: list,
    anisotropy: Anisotropy,
    samples: int | None,
    tolerance_de: float,
    energy: str,
) -> tuple[list, dict, AnisotropyChoice]:
    """(paints with their gloss moved into the anisotropic lobe, the lobe's uniforms, the sample choice).

    *order*: the renderer's lobe binding order; *cache*: (α_x, α_y) → (albedo texture, bound isotropic
    weights, sample choices), filled here and released by the renderer; *samples*: given count, else the
    level of detail's for *tolerance_de* ΔE00 (:func:`station.render.lod.choose_anisotropic_samples`);
    *energy*: :data:`station.render.anisotropy.ENERGIES`. The uniforms' ``_key`` names the cache entry
    whose texture the frame binds."""
    from station.render.lod import AnisotropyChoice, choose_anisotropic_samples
    from station.render.truth import sphere_pixels
    from station.render.weights import LobeWeights

    if energy not in an.ENERGIES:
        raise RenderInputError("anisotropy_energy", " | ".join(an.ENERGIES), energy)
    lobe = an.WardLobe.from_design(anisotropy)
    key = (lobe.alpha_x, lobe.alpha_y)
    if key not in cache:
        tex = tx.table_texture(ctx, an.albedo_table(lobe))
        w = an.fit_isotropic(basis.exponents, lobe.alpha_x)
        cache[key] = (tex, (w / w.sum())[order], {})
    _, w_bound, choices = cache[key]
    if samples is not None:
        an.sample_offsets(lobe, samples)  # validates
        choice = AnisotropyChoice(
            samples, float("nan"), float("nan"), f"{samples} anisotropic samples (given)"
        )
    else:
        ck = (float(tolerance_de), energy, lobe.tangent)
        if ck not in choices:
            choices[ck] = choose_anisotropic_samples(basis, lobe, *sphere_pixels(8), ck[0], energy=energy)
        choice = choices[ck]
    ps = [float(w.map_weights()[2].sum()) for w in pair]
    pair = [LobeWeights(w.exponents, w.k_d, w.k_dd, np.zeros_like(w.k_g), w.k_a) for w in pair]
    uniforms = {
        "_key": key,
        "u_aniso_samples": int(choice.samples) if lobe.spread > 0 else 1,
        "u_aniso_spread": lobe.spread,
        "u_aniso_hint": tuple(float(c) for c in lobe.tangent),
        "u_aniso_albedo": len(order) + 9,
        "u_aniso_cos_min": an.ALBEDO_COS_MIN,
        "u_aniso_ward_energy": int(energy == "ward"),
        "_aniso_w": w_bound,
        "_aniso_ps": (ps + ps)[:2],
    }
    return pair, uniforms, choice
