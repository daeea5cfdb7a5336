"""QA workflow for a seam: two panels (measured or designed), a misalignment, a range of geometries.

:func:`seam_qa` answers the QA engineer's questions (docs/design.md §1): how large is the predicted seam ΔE,
how much of it is geometric (identical paint, misaligned) and how much is formulation (the two paints
differ on aligned panels), what seam angle this paint tolerates (the goniogeometric index, eq 4.3.1),
pass or fail against a tolerance, the thesis's §4.5 styling guidelines applied to this case, and a
corrected second paint (inverse trompe l'oeil, §4.4) ready for formulation.

Under a chosen illuminant (``illuminant``, default D65): measured panels that carry spectra give their
Lab per geometry under that illuminant (:func:`measurements_under`: CIELAB relative to the
illuminant's own white, 10° observer), so the fitted designs, the seam ΔE and the correction are
those a viewer sees in a booth under it. Under D65 the stored Lab is used as before.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from station.analysis.errors import AnalysisInputError
from station.analysis.geometry import Hinge, SeamGeometry
from station.analysis.index import JND_CIE76, IndexResult, goniogeometric_index
from station.analysis.options import DEFAULT_ASPECULAR_DEG, DEFAULT_LIGHTS_DEG
from station.analysis.seam_model import SeamModel
from station.analysis.trompe import Objective, TrompeResult, inverse_trompe_loeil, paint_to_dict

#: Travel / lightness flop beyond which a paint counts as "high travel" in the advice.
HIGH_TRAVEL_DELTA_L = 30.0


def measurements_under(
    angles_deg: Sequence[float],
    spectra: Any,
    illuminant: str,
    gloss_gu: float | None = None,
    field: str = "panel",
) -> Any:
    """``AspecularMeasurements`` of a measured panel under *illuminant*, from its spectra.

    Parameters
    ----------
    angles_deg
        Aspecular angles (degrees, 45° illumination), one per spectrum.
    spectra
        Reflectance factors per angle, shape (n, 31) on 400–700 nm / 10 nm.
    illuminant
        A catalogue name (:func:`station.model.illuminants.illuminant_name`).
    gloss_gu
        60° gloss (GU) carried through.

    Raises
    ------
    AnalysisInputError
        Naming ``illuminant`` for an unknown name, ``FIELD.spectra`` for spectra of the wrong shape or range.
    """
    from station.model import AspecularMeasurements
    from station.model.errors import ModelInputError
    from station.model.spectra import reflectance_to_lab

    name = _illuminant(illuminant)
    arr = np.asarray(spectra, dtype=float)
    if arr.ndim != 2 or arr.shape[0] != len(angles_deg):
        raise AnalysisInputError(f"{field}.spectra", f"{len(angles_deg)} spectra (one per angle)", arr.shape)
    try:
        lab = reflectance_to_lab(arr, name)
    except ModelInputError as exc:
        raise AnalysisInputError(f"{field}.spectra", exc.accepted, exc.got) from exc
    return AspecularMeasurements(tuple(float(a) for a in angles_deg), lab, gloss_gu, illuminant=name)


def _illuminant(name: str) -> str:
    from station.model.errors import ModelInputError
    from station.model.illuminants import illuminant_name

    try:
        return illuminant_name(name)
    except ModelInputError as exc:
        raise AnalysisInputError("illuminant", exc.accepted, name) from exc


def as_paint(panel: Any, field: str = "panel", illuminant: str = "D65") -> Any:
    """A ``FaceFlopTravelGloss`` from a design or from ``AspecularMeasurements`` (fitted, eqs 3.3.x).

    Under an *illuminant* other than D65 only measurements taken under it
    (:func:`measurements_under`) are accepted: a design's Lab, and a measurement's stored Lab, are D65's.
    """
    from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg

    name = _illuminant(illuminant)
    if name != "D65" and isinstance(panel, AspecularMeasurements) and panel.illuminant != name:
        raise AnalysisInputError(
            field, f"a measurement with spectra, its Lab taken under {name}", f"Lab under {panel.illuminant}"
        )
    if isinstance(panel, FaceFlopTravelGloss):
        if name != "D65":
            raise AnalysisInputError(
                field,
                f"a measurement with spectra to judge under {name} (a design's Lab is D65's)",
                "a design",
            )
        return panel
    if isinstance(panel, AspecularMeasurements):
        return fit_fftg(panel).design
    raise AnalysisInputError(
        field, "a FaceFlopTravelGloss design or AspecularMeasurements", type(panel).__name__
    )


@dataclass(frozen=True)
class SeamReport:
    """Result of :func:`seam_qa` (all ΔE in the units of *method*; angles in degrees)."""

    paint_a: Any
    paint_b: Any
    beta_deg: float
    hinge: Any
    method: str
    tolerance: float
    geometries: tuple[SeamGeometry, ...]
    seam_de: tuple[float, ...]
    geometric_de: tuple[float, ...]
    formulation_de: tuple[float, ...]
    index: IndexResult
    passed: bool
    diagnosis: str
    advice: tuple[str, ...]
    correction: TrompeResult
    illuminant: str = "D65"

    @property
    def worst(self) -> int:
        """Index of the geometry with the largest seam ΔE."""
        return int(np.argmax(self.seam_de))

    def to_dict(self) -> dict[str, Any]:
        """JSON-able report."""
        return {
            "paint_a": paint_to_dict(self.paint_a),
            "paint_b": paint_to_dict(self.paint_b),
            "beta_deg": self.beta_deg,
            "hinge": self.hinge if isinstance(self.hinge, str) else float(self.hinge),
            "method": self.method,
            "illuminant": self.illuminant,
            "tolerance": self.tolerance,
            "seam_de_max": float(max(self.seam_de)),
            "seam_de_rms": float(np.sqrt(np.mean(np.square(self.seam_de)))),
            "worst_geometry": self.geometries[self.worst].to_dict(),
            "geometric_de_max": float(max(self.geometric_de)),
            "formulation_de_max": float(max(self.formulation_de)),
            "passed": self.passed,
            "diagnosis": self.diagnosis,
            "index": self.index.to_dict(),
            "advice": list(self.advice),
            "corrected_paint": paint_to_dict(self.correction.paint),
            "corrected_seam_de_max": self.correction.max_after,
            "corrected_meets_tolerance": self.correction.meets_epsilon,
            "correction_message": self.correction.message,
            "geometries": [
                {**g.to_dict(), "seam_de": s, "geometric_de": gd, "formulation_de": fd}
                for g, s, gd, fd in zip(
                    self.geometries, self.seam_de, self.geometric_de, self.formulation_de, strict=True
                )
            ],
        }


def seam_qa(
    panel_a: Any,
    panel_b: Any,
    beta_deg: float,
    *,
    lights_deg: Sequence[float] = DEFAULT_LIGHTS_DEG,
    aspecular_deg: Sequence[float] = DEFAULT_ASPECULAR_DEG,
    tolerance: float = JND_CIE76,
    method: str = "cie76",
    hinge: Hinge = "in-plane",
    objective: Objective = "minimax",
    illuminant: str = "D65",
) -> SeamReport:
    """Predict and judge a seam; propose a corrected paint for panel B.

    Parameters
    ----------
    panel_a, panel_b
        Designs (``FaceFlopTravelGloss``) or measurements (``AspecularMeasurements``, fitted first).
    beta_deg
        Signed misalignment of panel B in degrees (see :mod:`station.analysis.geometry`).
    lights_deg, aspecular_deg
        Geometries: every light (signed polar, degrees) with every aspecular angle on panel A (views
        beyond 89° from the normal are dropped).
    tolerance
        Seam ΔE accepted (default one JND, 2.3 ΔE*ab); also ε of the index.
    method
        ΔE formula.
    objective
        Objective of the correction (``"minimax"`` default, or ``"rms"``).
    illuminant
        The illuminant the seam is judged under (default D65); other than D65 the panels must be
        measurements under it (:func:`measurements_under`), see :func:`as_paint`.

    Returns
    -------
    SeamReport
    """
    a = as_paint(panel_a, "panel_a", illuminant)
    b = as_paint(panel_b, "panel_b", illuminant)
    ls, vs = _geometries(lights_deg, aspecular_deg)
    _check_beta(beta_deg)
    model = SeamModel(ls, vs, hinge=hinge, method=method)
    beta = np.array([float(beta_deg)])
    seam = model.delta_e(a, b, beta)[:, 0]
    geometric = model.delta_e(a, a, beta)[:, 0]
    formulation = model.difference(model.reference(a), model.reference(b))[:, 0]
    index = (
        goniogeometric_index(a, ls, vs, epsilon=tolerance, method=method, hinge=hinge)
        if len(ls) == 1
        else _index_over(a, ls, vs, tolerance, method, hinge)
    )
    passed = bool(np.max(seam) <= tolerance)
    diagnosis = _diagnosis(seam, geometric, formulation, tolerance)
    correction = _correction(a, ls, vs, float(beta_deg), objective, hinge, method, tolerance)
    geoms = tuple(SeamGeometry(lt, v, hinge) for lt, v in zip(ls, vs, strict=True))
    advice = _advice(a, float(beta_deg), index, seam, geoms, correction, tolerance, hinge, method)
    return SeamReport(
        a,
        b,
        float(beta_deg),
        hinge,
        method,
        float(tolerance),
        geoms,
        tuple(float(x) for x in seam),
        tuple(float(x) for x in geometric),
        tuple(float(x) for x in formulation),
        index,
        passed,
        diagnosis,
        advice,
        correction,
        _illuminant(illuminant),
    )


def _geometries(
    lights_deg: Sequence[float], aspecular_deg: Sequence[float]
) -> tuple[list[float], list[float]]:
    """Every light (signed polar, degrees) with every aspecular angle on panel A: parallel lists
    (lights, views) in degrees, views beyond 89° from the normal dropped."""
    ls, vs = [], []
    for lt in lights_deg:
        for asp in aspecular_deg:
            v = float(asp) - float(lt)
            if abs(v) <= 89.0:
                ls.append(float(lt))
                vs.append(v)
    if not ls:
        raise AnalysisInputError(
            "aspecular_deg", "aspecular angles reachable from the lights (|view| <= 89°)", list(aspecular_deg)
        )
    return ls, vs


def _check_beta(beta_deg: float) -> None:
    """Refuse a misalignment outside 0 < |β| <= 45 degrees (or not a number)."""
    try:
        beta_ok = bool(np.isfinite(float(beta_deg)) and 0.0 < abs(float(beta_deg)) <= 45.0)
    except (TypeError, ValueError):
        beta_ok = False
    if not beta_ok:
        raise AnalysisInputError("beta_deg", "0 < |β| <= 45 degrees", beta_deg)


def _correction(
    a: Any,
    ls: list[float],
    vs: list[float],
    beta_deg: float,
    objective: Objective,
    hinge: Hinge,
    method: str,
    tolerance: float,
) -> TrompeResult:
    """The corrected paint for panel B (inverse trompe l'oeil, §4.4), named after panel A's paint."""
    correction = inverse_trompe_loeil(
        a,
        ls,
        vs,
        beta_deg=beta_deg,
        objective=objective,
        subset="solid" if a.is_solid else "full",
        hinge=hinge,
        method=method,
        epsilon=tolerance,
    )
    name = f"{a.name or 'panel A paint'}, corrected for panel B ({beta_deg:+g}°)"
    return replace(
        correction,
        paint=correction.paint.replace(name=name),
        paints=tuple(p.replace(name=name) for p in correction.paints),
    )


def _index_over(
    a: Any, ls: list[float], vs: list[float], eps: float, method: str, hinge: Hinge
) -> IndexResult:
    """Index over paired geometries (lights[i], views[i]): the minimum over per-light calls."""
    best: IndexResult | None = None
    for lt in sorted(set(ls)):
        views = [v for l2, v in zip(ls, vs, strict=True) if l2 == lt]
        r = goniogeometric_index(a, lt, views, epsilon=eps, method=method, hinge=hinge)
        new, old = r.beta_min_deg, None if best is None else best.beta_min_deg  # None: ε not reached
        if best is None or (new is not None and (old is None or new < old)):
            best = r
    assert best is not None  # noqa: S101 - ls is non-empty
    return best


def _diagnosis(seam: np.ndarray, geometric: np.ndarray, formulation: np.ndarray, tol: float) -> str:
    g, f, s = float(np.max(geometric)), float(np.max(formulation)), float(np.max(seam))
    if s <= tol:
        return f"seam within tolerance (worst ΔE {s:.2f} ≤ {tol:g})"
    if f <= tol / 2 and g > tol / 2:
        return (
            f"geometric mismatch: the paints agree on aligned panels (ΔE ≤ {f:.2f}) but the misalignment "
            f"alone gives ΔE up to {g:.2f}; repainting will not fix it"
        )
    if g <= tol / 2 and f > tol / 2:
        return (
            f"formulation mismatch: the paints differ by ΔE up to {f:.2f} on aligned panels; the "
            f"misalignment alone gives only {g:.2f}"
        )
    return f"both: formulation ΔE up to {f:.2f} and geometric ΔE up to {g:.2f} (seam ΔE up to {s:.2f})"


def _advice(
    a: Any,
    beta: float,
    index: IndexResult,
    seam: np.ndarray,
    geoms: tuple[SeamGeometry, ...],
    correction: TrompeResult,
    tol: float,
    hinge: Hinge,
    method: str,
) -> tuple[str, ...]:
    """The thesis's §4.5 guidelines, applied to this paint and seam."""
    out: list[str] = []
    high_travel = (not a.is_solid) and (a.face[0] - a.flop[0]) >= HIGH_TRAVEL_DELTA_L
    bmin = index.beta_min_deg
    if high_travel:
        out.append(
            f"1) High-travel paint (L* {a.face[0]:.0f} → {a.flop[0]:.0f} over {a.travel_deg:.0f}°): use it "
            "only where seams of flush panels come together precisely parallel"
            + (f" (this paint tolerates {bmin:.2f}°, the seam is {abs(beta):.2f}°)." if bmin else ".")
        )
    if not a.is_solid and bmin is not None and abs(beta) >= bmin:
        from station.model import FaceFlopTravelGloss

        mid_l, mid_a, mid_b = (float(x) for x in a.lab_at(np.array([45.0])).reshape(3))
        mid = (mid_l, mid_a, mid_b)
        solid = FaceFlopTravelGloss(mid, mid, None)
        ls = sorted({g.light_deg for g in geoms})
        rs = goniogeometric_index(solid, ls, 0.0, epsilon=tol, method=method, hinge=hinge, beta_max_deg=45.0)
        tol_s = f"{rs.beta_min_deg:.2f}°" if rs.reached else "more than 45°"
        out.append(
            f"2) The seam is not flush: a solid or low-travel paint suits it better (a solid of this "
            f"paint's 45° colour tolerates {tol_s})."
        )
    worst = geoms[int(np.argmax(seam))]
    if worst.aspecular_deg <= 30.0 and float(np.max(seam)) > tol:
        out.append(
            f"3) The worst seam is seen at a low aspecular angle ({worst.aspecular_deg:.0f}°, light "
            f"{worst.light_deg:g}°): avoid seam orientations commonly viewed near the specular direction."
        )
    if bmin is not None:
        out.append(
            f"4) Manufacturing tolerance for this paint: keep the seam angle below {bmin:.2f}° "
            f"(ΔE {tol:g}, worst geometry light {index.geometry.get('light_deg')}°, aspecular "
            f"{index.geometry.get('aspecular_deg', float('nan')):.0f}°)."
        )
    else:
        out.append(
            f"4) This paint stays within ΔE {tol:g} up to {index.beta_max_deg:g}° of misalignment over "
            "these geometries; the tolerance can be set by other criteria."
        )
    if correction.meets_epsilon:
        out.append(
            f"5) Over this limited range of views, an inverse trompe l'oeil paint for panel B brings the "
            f"worst seam from {correction.max_before:.2f} to {correction.max_after:.2f} ΔE."
        )
    else:
        out.append(
            f"5) No single second paint hides this seam over the whole range (best worst-case ΔE "
            f"{correction.max_after:.2f}); choose seam placements that limit the range of viewing angles."
        )
    return tuple(out)
