"""Thesis chapter 4: the goniogeometric index and inverse trompe l'oeil (§4.3–4.4, Figs 4.4–4.7).

* **Lambertian index against its closed form.** For a solid under a point light the panel colour is the
  paint's tristimulus values scaled by k = cos(θ_i + β)/cos θ_i (eqs 4.3.2–4.3.3 with erratum 2, L·N, and
  the reference exposure of docs/misalignment.md). Above CIELAB's linear segment every channel of
  (L* + 16, a*, b*) then scales by k^⅓, so ΔE*ab(β) = |k^⅓ − 1|·‖(L* + 16, a*, b*)‖ and eq 4.3.1 has the
  closed form β_min = arccos((1 − ε/R)³ cos θ_i) − θ_i (turning away), or θ_i − arccos((1 + ε/R)³ cos θ_i)
  (turning towards, where (1 + ε/R)³ cos θ_i ≤ 1), the smaller of the two, R = ‖(L* + 16, a*, b*)‖.
* **Fig. 4.4** from :func:`station.analysis.scenarios.solid_panels`.
* **Figs 4.5–4.7.** Ours (:mod:`station.analysis.scenarios`: face at 15°, mirror law, L·N) beside a
  *thesis convention* mode (:func:`thesis_convention_solve`): the face at 0° aspecular as §4.3.3 writes g
  (the convention docs/design.md erratum 3 corrects), panel B seeing every aspecular angle shifted by β
  (not the 2β of the mirror law for an in-plane turn), and the shading of eq 4.3.2 as printed (L·V, which
  a turn of the panel leaves unchanged) or with erratum 2 (L·N). In that mode the exact solution is the
  shifted curve X_B(θ) = X_A(θ − β), a member of the model family with travel θ_flop + β for *any* paint:
  +2.0° for the 2° silver and +8° for the 8° bumper, the thesis's two travel numbers. The face change
  depends on the paint, which the thesis does not give.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.analysis import goniogeometric_index
from station.analysis.index import JND_CIE76
from station.analysis.scenarios import (
    BUMPER_BETA_DEG,
    BUMPER_PAINT,
    INSTRUMENT_ASPECULAR,
    SILVER_BETA_DEG,
    SILVER_PAINT,
    SOLID_BETA_DEG,
    SOLID_LIGHTS_DEG,
    SOLID_PAINT,
    bumper_fender,
    silver_black_flop,
    solid_panels,
)
from station.model import FaceFlopTravelGloss
from station.model.domain import FACE_ANGLE_DEG
from station.model.shading import shade_lab
from station.reproduce.core import ExperimentResult, Figure, Quantity
from station.reproduce.errors import ReproduceInputError

if TYPE_CHECKING:
    from station.analysis.trompe import TrompeResult

Shading = Literal["printed", "lambert"]
#: The thesis's face angle in §4.3.3 ("g … goes from C_face at 0 aspecular angle"), degrees.
THESIS_FACE_ANGLE_DEG = 0.0
#: Light polar angle of the instrument geometries of Figs 4.5–4.7 (degrees from the normal).
LIGHT_DEG = 45.0


def lambertian_index_closed_form(lab: Sequence[float], light_deg: float, epsilon: float = JND_CIE76) -> float:
    """β_min in degrees of a solid under a point light at *light_deg* (module docstring).

    Valid while the shaded colour stays above CIELAB's linear segment (Y/Y_n > (6/29)³).
    """
    r = math.sqrt((lab[0] + 16.0) ** 2 + lab[1] ** 2 + lab[2] ** 2)
    ti = math.radians(abs(light_deg))
    away = math.degrees(math.acos((1.0 - epsilon / r) ** 3 * math.cos(ti)) - ti)
    toward_k = (1.0 + epsilon / r) ** 3 * math.cos(ti)
    if toward_k <= 1.0:
        return min(away, math.degrees(ti - math.acos(toward_k)))
    return away


def lambertian_index(out_dir: Path | None) -> ExperimentResult:
    """§4.3.2: the numeric index of a solid against the closed form, at the Fig. 4.4 light angles."""
    t0 = time.perf_counter()
    quantities = []
    for light in SOLID_LIGHTS_DEG:
        ours = goniogeometric_index(SOLID_PAINT, light, direction="either")
        if ours.beta_min_deg is None:  # pragma: no cover - ε is reached well inside 30° for this paint
            raise ReproduceInputError("light_deg", "a light under which ε is reached", light)
        quantities.append(
            Quantity(
                "§4.3.2",
                f"β_min of a solid, light at {light:g}°",
                "deg",
                lambertian_index_closed_form(SOLID_PAINT.face, light),
                ours.beta_min_deg,
                1e-4,
                source="closed form of eqs 4.3.1–4.3.3 (erratum 2: L·N)",
            )
        )
    notes = (
        f"Paint {SOLID_PAINT.name} Lab {SOLID_PAINT.face}, ε = {JND_CIE76} ΔE*ab, either direction. The "
        "numeric root finder (stated resolution 1e-6°) against "
        "β_min = arccos((1 − ε/R)³ cos θ_i) − θ_i, R = ‖(L* + 16, a*, b*)‖."
    )
    return ExperimentResult("ch4-lambertian", tuple(quantities), (), notes, time.perf_counter() - t0)


def _fig44_picture(out_dir: Path, panels: dict[str, object]) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from station.analysis.picture import SOLID_GRID_COLUMNS, draw_solid_grid

    fig, axes = plt.subplots(len(SOLID_LIGHTS_DEG), len(SOLID_GRID_COLUMNS), figsize=(8, 8))
    draw_solid_grid(axes, SOLID_PAINT, panels, SOLID_LIGHTS_DEG, SOLID_BETA_DEG, (36, 72))
    fig.suptitle("Fig. 4.4 on our code: solid, 3° misalignment, seam ΔE*ab", fontsize=10)
    fig.tight_layout()
    path = out_dir / "ch4-fig4.4.png"
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return Figure("4.4", path, "Rows: light angle; columns: the thesis's four techniques; ΔE*ab below each.")


def fig44(out_dir: Path | None) -> ExperimentResult:
    """Fig. 4.4: inverse trompe l'oeil for a solid, 3° misalignment, six light angles."""
    t0 = time.perf_counter()
    s = solid_panels()
    i0, i45 = SOLID_LIGHTS_DEG.index(0.0), SOLID_LIGHTS_DEG.index(45.0)
    quantities = (
        Quantity(
            "4.4",
            "optimised at 45°: seam ΔE at the 0° light",
            "ΔE*ab",
            2.0,
            s["single_45"].seam_de_after[i0],
            0.5,
            source="§4.4.1 'quite poor at 0°, about 2 ΔE'",
            reason="the thesis's paint is not given; ours is a light blue-grey solid (75, −5, −20)",
        ),
        Quantity(
            "4.4",
            "optimised at 45°: seam ΔE at 45°",
            "ΔE*ab",
            0.0,
            s["single_45"].seam_de_after[i45],
            0.01,
            source="§4.4.1 'a perfect match at 45.0°'",
        ),
        Quantity(
            "4.4",
            "RMS solution: worst seam ΔE",
            "ΔE*ab",
            1.0,
            s["rms"].max_after,
            0.25,
            source="§4.4.1 'the worst error is about 1 ΔE'",
        ),
        Quantity(
            "4.4",
            "per row: worst seam ΔE",
            "ΔE*ab",
            0.0,
            s["per_geometry"].max_after,
            0.05,
            source="§4.4.1 'effectively eliminate the appearance of the geometric misalignment'",
        ),
    )
    figures = (_fig44_picture(out_dir, dict(s)),) if out_dir is not None else ()
    notes = (
        "Seam ΔE*ab per light (rows 0, 15.5, 29.1, 39.8, 45, 52°): identical "
        + ", ".join(f"{v:.2f}" for v in s["rms"].seam_de_before)
        + "; optimised at 45° "
        + ", ".join(f"{v:.2f}" for v in s["single_45"].seam_de_after)
        + "; RMS "
        + ", ".join(f"{v:.2f}" for v in s["rms"].seam_de_after)
        + ". Our numbers scale with L* + 16 of the (unstated) paint."
    )
    return ExperimentResult("ch4-fig4.4", quantities, figures, notes, time.perf_counter() - t0)


def effect_lab(
    face: ArrayLike,
    flop: ArrayLike,
    travel_deg: float,
    angles_deg: NDArray[np.float64],
    face_angle_deg: float,
) -> NDArray[np.float64]:
    """Clamped quadratic with its face at *face_angle_deg* (eqs 3.3.1–3.3.2 with a free face angle).

    X(θ) = flop + (face − flop)·((θ_c − min(|θ|, θ_c)) / (θ_c − θ_face))². With θ_face = 15° this is
    :meth:`FaceFlopTravelGloss.lab_at`; θ_face = 0° is the thesis's g of §4.3.3 (erratum 3).
    """
    th = np.minimum(np.abs(angles_deg), travel_deg)
    s = (travel_deg - th) / (travel_deg - face_angle_deg)
    return np.asarray(flop, float) + (np.asarray(face, float) - np.asarray(flop, float)) * (s * s)[:, None]


@dataclass(frozen=True)
class ConventionResult:
    """Paint B of an inverse trompe l'oeil solve under a stated convention (changes: B − A)."""

    face_change: tuple[float, float, float]
    flop_change: tuple[float, float, float]
    travel_change_deg: float
    rms_before: float
    rms_after: float


def thesis_convention_solve(
    paint: FaceFlopTravelGloss,
    beta_deg: float,
    *,
    full: bool,
    face_angle_deg: float = THESIS_FACE_ANGLE_DEG,
    shift_per_beta: float = 1.0,
    shading: Shading = "printed",
    aspecular_deg: Sequence[float] = INSTRUMENT_ASPECULAR,
    light_deg: float = LIGHT_DEG,
) -> ConventionResult:
    """Inverse trompe l'oeil (RMS ΔE*ab) for panel B turned away from the light by |β| (degrees).

    Panel B sees every aspecular angle α of *aspecular_deg* as α + shift_per_beta·|β| (1: the thesis's
    figures; 2: the mirror law for an in-plane turn) and is shaded by k = 1 (``"printed"``: eq 4.3.2's
    L·V, unchanged by the turn) or k = cos(θ_l + |β|)/cos θ_l (``"lambert"``, erratum 2). Free: face L*
    and travel (``full=False``, Fig. 4.5) or all seven numbers (``full=True``, Figs 4.6–4.7).
    """
    from scipy.optimize import least_squares

    if shading not in ("printed", "lambert"):
        raise ReproduceInputError("shading", "printed | lambert", shading)
    if paint.travel_deg is None:
        raise ReproduceInputError("paint", "an effect paint (travel_deg set)", paint.name)
    travel = paint.travel_deg
    angles = np.asarray(aspecular_deg, dtype=float)
    beta = abs(beta_deg)
    lab_a = effect_lab(paint.face, paint.flop, travel, angles, face_angle_deg)
    angles_b = angles + shift_per_beta * beta
    k = (
        math.cos(math.radians(light_deg + beta)) / math.cos(math.radians(light_deg))
        if shading == "lambert"
        else 1.0
    )
    kk = np.full(angles.size, k)

    def unpack(x: NDArray[np.float64]) -> tuple[NDArray, NDArray, float]:
        if full:
            return x[0:3], x[3:6], float(x[6])
        return np.array([x[0], paint.face[1], paint.face[2]]), np.asarray(paint.flop, float), float(x[1])

    def residual(x: NDArray[np.float64]) -> NDArray[np.float64]:
        face, flop, tc = unpack(x)
        lab_b = shade_lab(effect_lab(face, flop, max(tc, face_angle_deg + 1.0), angles_b, face_angle_deg), kk)
        return (lab_b - lab_a).ravel()

    x0 = np.r_[paint.face, paint.flop, travel] if full else np.r_[paint.face[0], travel]
    before = residual(x0).reshape(-1, 3)
    sol = least_squares(residual, x0, xtol=1e-12, ftol=1e-12, gtol=1e-12)
    after = sol.fun.reshape(-1, 3)
    face, flop, tc = unpack(sol.x)

    def rms(r: NDArray[np.float64]) -> float:
        return float(np.sqrt(np.mean(np.sum(r * r, axis=-1))))

    return ConventionResult(
        tuple(float(v) for v in face - np.asarray(paint.face)),  # type: ignore[arg-type]
        tuple(float(v) for v in flop - np.asarray(paint.flop)),  # type: ignore[arg-type]
        tc - travel,
        rms(before),
        rms(after),
    )


def implied_face_flop_difference(face_change: float, travel_deg: float, shift_deg: float) -> float:
    """face − flop (L*) of a paint for which the thesis convention's exact solution raises the face by
    *face_change*: (face − flop)·((1 + δ/θ_flop)² − 1) = Δface (face at 0°, no shading change)."""
    return face_change / ((1.0 + shift_deg / travel_deg) ** 2 - 1.0)


def _fig45_picture(
    out_dir: Path, ours_face: float, ours_travel: float, tc_face: float, tc_travel: float
) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = SILVER_PAINT
    assert p.travel_deg is not None  # noqa: S101
    beta = abs(SILVER_BETA_DEG)
    theta = np.linspace(0.0, 120.0, 241)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    for ax, face_angle, shift, dface, dtravel, title in (
        (axes[0], FACE_ANGLE_DEG, 2.0, ours_face, ours_travel, "ours: face at 15°, mirror law (2β), L·N"),
        (
            axes[1],
            THESIS_FACE_ANGLE_DEG,
            1.0,
            tc_face,
            tc_travel,
            "thesis convention: face at 0°, shift β, L·V",
        ),
    ):
        a = effect_lab(p.face, p.flop, p.travel_deg, theta, face_angle)[:, 0]
        seen = effect_lab(p.face, p.flop, p.travel_deg, theta + shift * beta, face_angle)[:, 0]
        b_face = (p.face[0] + dface, 0.0, 0.0)
        b = effect_lab(b_face, p.flop, p.travel_deg + dtravel, theta + shift * beta, face_angle)[:, 0]
        ax.plot(theta, a, "k-", lw=2, label="panel A, paint A")
        ax.plot(theta, seen, "C3--", label="panel B, paint A (mismatch)")
        ax.plot(
            theta, b, "C0:", lw=2, label=f"panel B, paint B: Δface L* {dface:+.1f}, Δtravel {dtravel:+.1f}°"
        )
        for x in INSTRUMENT_ASPECULAR:
            ax.axvline(x, color="0.85", lw=0.8, zorder=0)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("aspecular angle on panel A (deg)")
        ax.set_ylabel("L*")
        ax.legend(fontsize=7)
    fig.suptitle(
        "Fig. 4.5: silver, black flop, 2° misalignment (thesis: Δface L* +3.4, Δtravel +2.0°)", fontsize=10
    )
    path = out_dir / "ch4-fig4.5.png"
    fig.savefig(path, dpi=85)
    plt.close(fig)
    return Figure(
        "4.5", path, "L* against aspecular angle as seen on both panels; grey lines: the five geometries."
    )


def figs45_47(out_dir: Path | None) -> ExperimentResult:
    """Figs 4.5–4.7: ours beside the thesis convention (module docstring)."""
    t0 = time.perf_counter()
    silver = silver_black_flop()
    bumper = bumper_fender()
    ts = thesis_convention_solve(SILVER_PAINT, SILVER_BETA_DEG, full=False)
    tb = thesis_convention_solve(BUMPER_PAINT, BUMPER_BETA_DEG, full=True)
    tb_lam = thesis_convention_solve(BUMPER_PAINT, BUMPER_BETA_DEG, full=True, shading="lambert")
    mirror = (
        "mirror law: turning the panel in plane by β turns the specular direction by 2β, so panel B sees "
        "every aspecular angle shifted by 2β and the exact fix moves the travel by ≈ 2β; the thesis's "
        "travel equals β (see the thesis-convention rows)"
    )
    quantities = (*_fig45_quantities(silver, ts, mirror), *_fig46_47_quantities(bumper, tb, tb_lam, mirror))
    figures = (
        (
            _fig45_picture(
                out_dir,
                silver.changes["face_L"],
                silver.changes["travel_deg"],
                ts.face_change[0],
                ts.travel_change_deg,
            ),
        )
        if out_dir is not None
        else ()
    )
    notes = _figs45_47_notes(silver, bumper, ts, tb)
    return ExperimentResult("ch4-figs4.5-4.7", quantities, figures, notes, time.perf_counter() - t0)


def _fig45_quantities(silver: TrompeResult, ts: ConventionResult, mirror: str) -> tuple[Quantity, ...]:
    """Fig. 4.5 (silver, black flop, β = 2°): travel and face L* changes, ours and the thesis convention."""
    assert SILVER_PAINT.travel_deg is not None  # noqa: S101
    implied = implied_face_flop_difference(3.4, SILVER_PAINT.travel_deg, abs(SILVER_BETA_DEG))
    return (
        Quantity(
            "4.5",
            "Δ travel, ours (in-plane)",
            "deg",
            2.0,
            silver.changes["travel_deg"],
            0.5,
            reason=mirror,
            source="§4.4.2 'travel increases by 2.0 degrees'",
        ),
        Quantity(
            "4.5",
            "Δ face L*, ours (in-plane)",
            "ΔL*",
            3.4,
            silver.changes["face_L"],
            1.0,
            reason="2β shift (mirror law) on the steep part of the curve next to the 15° face (erratum 3), "
            "plus the L·N shading of panel B (erratum 2); the thesis's paint is not given",
            source="§4.4.2 'face L increases by 3.4 units'",
        ),
        Quantity(
            "4.5",
            "Δ travel, thesis convention",
            "deg",
            2.0,
            ts.travel_change_deg,
            0.5,
            source="§4.4.2; face at 0°, shift β, L·V: the exact fix is the curve shifted by β",
        ),
        Quantity(
            "4.5",
            "Δ face L*, thesis convention (our silver 100 → 5, 60°)",
            "ΔL*",
            3.4,
            ts.face_change[0],
            1.0,
            reason="the face change scales with the unstated paint's face − flop: the thesis's +3.4 follows "
            f"for face − flop = {implied:.0f} L* at a 60° travel (ours: 95)",
            source="§4.4.2",
        ),
    )


def _fig46_47_quantities(
    bumper: TrompeResult, tb: ConventionResult, tb_lam: ConventionResult, mirror: str
) -> tuple[Quantity, ...]:
    """Figs 4.6–4.7 (bumper and fender, full FFTG): the flop angle's change and the face's chroma."""
    b_face_c = math.hypot(BUMPER_PAINT.face[1] + tb.face_change[1], BUMPER_PAINT.face[2] + tb.face_change[2])
    a_face_c = math.hypot(BUMPER_PAINT.face[1], BUMPER_PAINT.face[2])
    return (
        Quantity(
            "4.6–4.7",
            "Δ θ_flop, ours (in-plane, full FFTG)",
            "deg",
            8.0,
            bumper.changes["travel_deg"],
            1.5,
            reason=mirror,
            source="§4.4.2 'approximately 8° more than the original'",
        ),
        Quantity(
            "4.6–4.7",
            "Δ θ_flop, thesis convention (full FFTG)",
            "deg",
            8.0,
            tb.travel_change_deg,
            1.5,
            source="§4.4.2",
        ),
        Quantity(
            "4.6–4.7",
            "Δ θ_flop, thesis convention with L·N shading",
            "deg",
            8.0,
            tb_lam.travel_change_deg,
            1.5,
            source="§4.4.2",
        ),
        Quantity(
            "4.6–4.7",
            "face more chromatic, thesis convention: ΔC*",
            "ΔC*",
            0.0,
            b_face_c - a_face_c,
            0.0,
            mode="at_least",
            source="§4.4.2 'the face color is brighter and more chromatic'",
        ),
    )


def _figs45_47_notes(
    silver: TrompeResult, bumper: TrompeResult, ts: ConventionResult, tb: ConventionResult
) -> str:
    """Why ours differ from Figs 4.5–4.7, with the RMS before and after of each solve (ΔE*ab)."""
    return (
        "Why ours differ. (1) §4.3.3 writes g from the face at 0° aspecular; §3.3 (and we) put it at 15° "
        "(erratum 3). (2) An in-plane turn by β moves the specular direction by 2β; the thesis's travel "
        "changes equal β in both figures (+2.0° for 2°, ≈ +8° for 8°), which is what a shift of β gives for "
        "any paint: X_B(θ) = X_A(θ − β) is in the model family with travel θ_flop + β. So the figures "
        "shifted the aspecular angle by β (only one of light and view turned, against §4.3.1's 'rotating "
        "the lighting and viewing geometry by β'). (3) Out of plane, the aspecular change is second order: "
        "ours +1.4 face L*, +0.0° travel for the silver (docs/misalignment.md), so the thesis's numbers are "
        "in-plane ones (§4.3.3: 'only considers in-plane reflections'). (4) The caption of Fig. 4.5 says 3°, "
        "the text 2°; only 2° with a shift of β gives +2.0°. "
        f"Thesis convention, silver: RMS {ts.rms_before:.2f} → {ts.rms_after:.3f} ΔE*ab; bumper: "
        f"{tb.rms_before:.2f} → {tb.rms_after:.3f}, face ΔL* {tb.face_change[0]:+.1f}, flop ΔL* "
        f"{tb.flop_change[0]:+.1f}. Ours, silver: RMS {silver.rms_before:.2f} → {silver.rms_after:.2f}; "
        f"bumper {bumper.rms_before:.2f} → {bumper.rms_after:.2f}."
    )


#: β step of the Fig. 4.3 sweep (degrees).
FIG43_STEP_DEG = 0.05


def fig43(out_dir: Path | None) -> ExperimentResult:
    """Fig. 4.3: the index read off the seam-ΔE curves (§4.3.3) against the root of eq 4.3.1."""
    from station.analysis import plot_sweep, seam_sweep

    t0 = time.perf_counter()
    b = np.round(np.arange(FIG43_STEP_DEG, 3.0 + 1e-9, FIG43_STEP_DEG), 6)
    lights = [15.0, 30.0, 45.0, 60.0]
    views = [float(v) for v in np.arange(-80.0, 81.0, 2.0)]
    sweep = seam_sweep(BUMPER_PAINT, list(np.concatenate([-b[::-1], b])), lights, views)
    root = goniogeometric_index(BUMPER_PAINT, lights, views, direction="either")
    graphical = sweep.index_estimate()
    if graphical is None or root.beta_min_deg is None:  # pragma: no cover - ε is crossed inside 3°
        raise ReproduceInputError("betas", "a sweep that crosses ε", None)
    quantities = (
        Quantity(
            "4.3",
            f"graphical index from the curves ({FIG43_STEP_DEG:g}° steps) against the root of eq 4.3.1",
            "deg",
            root.beta_min_deg,
            graphical,
            FIG43_STEP_DEG,
            source="§4.3.3: 'one selects the curve which is below the acceptable color difference threshold'",
            reference="eq 4.3.1",
        ),
    )
    figures: tuple[Figure, ...] = ()
    if out_dir is not None:
        coarse = seam_sweep(BUMPER_PAINT, [-8.0, -3.0, -1.0, -0.3, 0.3, 1.0, 3.0, 8.0], lights, views)
        path = plot_sweep(coarse, out_dir / "ch4-fig4.3.png", title="Fig. 4.3 on our code: blue metallic")
        figures = (
            Figure("4.3", path, "Seam ΔE*ab against view (light 45°) and light (view 0°), one curve per β."),
        )
    notes = (
        f"{BUMPER_PAINT.name}: β_min = {root.beta_min_deg:.4f}° at light {root.geometry['light_deg']:g}°, view "
        f"{root.geometry['view_deg']:g}° (in plane); the curves give {graphical:g}°."
    )
    return ExperimentResult("ch4-fig4.3", quantities, figures, notes, time.perf_counter() - t0)
