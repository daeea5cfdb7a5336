"""Recipes as masses: a batch in grams, and the tinting additions a correction asks for.

A recipe holds mass fractions c_i of the basecoat (colorants; the rest, 1 − Σ c_i, is binder). For a
batch of M grams:

* colorant i: m_i = c_i M; binder: m_b = (1 − Σ c_i) M; total M.

A correction to fractions c′ is made by **adding** to the batch already mixed (nothing can be taken
out of a can): the smallest new batch M′ with c′_i M′ ≥ c_i M for every component (colorants and
binder) is M′ = M · max_i (c_i / c′_i) over the components present in the batch, and the additions are
a_i = c′_i M′ − c_i M ≥ 0. A component the correction removes entirely (c′_i = 0 < c_i) cannot be
reached by additions: the batch must be remade, which :class:`Tinting` says.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from station.formulate.errors import FormulateInputError

#: Default batch size (g) the CLI and the service report a recipe in.
DEFAULT_BATCH_G = 1000.0
#: Largest batch 1 kg may grow to by tinting before a remake is the sensible advice (factor).
MAX_GROWTH = 3.0
#: Largest batch (g) a recipe is weighed out for or formulated at (the scale's and the service's ceiling).
MAX_BATCH_G = 1e6


#: Decimals of a gram that a weighed-out mass keeps (1 ng): below every scale's resolution, above float noise.
MASS_DECIMALS = 9


def _check_batch(batch_g: float) -> float:
    if not (np.isfinite(batch_g) and 0 < batch_g <= MAX_BATCH_G):
        raise FormulateInputError("batch_g", f"0 < batch_g <= {MAX_BATCH_G:g} g", batch_g)
    return float(batch_g)


def _binder(recipe: dict[str, float]) -> float:
    total = float(sum(recipe.values()))
    if any(not np.isfinite(v) or v < 0 for v in recipe.values()) or total > 1.0 + 1e-9:
        raise FormulateInputError("recipe", "mass fractions >= 0 summing to <= 1", recipe)
    return max(0.0, 1.0 - total)


@dataclass(frozen=True)
class Batch:
    """A recipe weighed out: grams per colorant, the binder and the total (g)."""

    colorants_g: dict[str, float]
    binder_g: float
    total_g: float

    def to_dict(self) -> dict[str, object]:
        """JSON-able form: the fields as they are."""
        return asdict(self)


def batch_masses(recipe: dict[str, float], batch_g: float = DEFAULT_BATCH_G) -> Batch:
    """Weigh *recipe* (mass fractions) out as a batch of *batch_g* grams (module docstring). Masses are
    rounded to :data:`MASS_DECIMALS` decimals of a gram (far below any scale), so that a fraction times the
    batch carries no binary residue: 0.0097 of 1000 g is 9.7 g, not 9.700000000000001 g."""
    m = _check_batch(batch_g)
    binder = _binder(recipe)
    return Batch(
        {k: round(float(v) * m, MASS_DECIMALS) for k, v in recipe.items()},
        round(binder * m, MASS_DECIMALS),
        m,
    )


@dataclass(frozen=True)
class Tinting:
    """Additions (g) that turn a mixed batch into a corrected recipe.

    ``additions_g`` per colorant (and ``binder_g``); ``new_total_g`` the batch after them; ``remake``
    True when additions cannot reach the recipe (a colorant must be removed) or the batch would grow
    more than :data:`MAX_GROWTH` times, with ``message`` saying which.
    """

    additions_g: dict[str, float]
    binder_g: float
    new_total_g: float
    remake: bool
    message: str

    def to_dict(self) -> dict[str, object]:
        """JSON-able form: the fields as they are."""
        return asdict(self)


def tinting_additions(
    before: dict[str, float], after: dict[str, float], batch_g: float = DEFAULT_BATCH_G
) -> Tinting:
    """Additions turning a batch of *batch_g* g mixed to *before* into *after* (module docstring)."""
    m = _check_batch(batch_g)
    names = sorted(set(before) | set(after))
    c0 = np.array([before.get(n, 0.0) for n in names] + [_binder(before)])
    c1 = np.array([after.get(n, 0.0) for n in names] + [_binder(after)])
    present = c0 > 1e-9
    removed = [n for n, p, q in zip([*names, "binder"], c0, c1, strict=True) if p > 1e-9 and q <= 1e-9]
    if removed:
        return Tinting({}, 0.0, m, True, f"remake the batch: the correction removes {', '.join(removed)}")
    growth = float(np.max(c0[present] / c1[present])) if present.any() else 1.0
    growth = max(growth, 1.0)
    add = np.clip(c1 * m * growth - c0 * m, 0.0, None)
    additions = {n: float(a) for n, a in zip(names, add[:-1], strict=True) if a > 1e-6}
    total = m * growth
    if growth > MAX_GROWTH:
        return Tinting(
            additions,
            float(add[-1]),
            total,
            True,
            f"remake the batch: tinting would grow it {growth:.1f}× (over {MAX_GROWTH:g}×)",
        )
    return Tinting(additions, float(add[-1]), total, False, f"add to the {m:g} g batch: {total:.1f} g after")
