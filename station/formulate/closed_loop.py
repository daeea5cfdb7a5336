"""Closed-loop prototyping: recipe → spray-out → measurement → ΔE → correction (beyond the thesis).

Labs iterate: they spray the formulated recipe, measure the panel, and correct the recipe by the
difference between what the model predicted and what the panel shows. :func:`closed_loop` does that
with the measuring injected as a callable ``measure(recipe) -> AspecularMeasurements`` (this package
may not import the drivers). Every front (``station formulate --closed-loop``, the service's
``POST /formulation/closed-loop``, the viewer's "Run closed loop") passes the in-process SYNTHETIC
:class:`~station.formulate.sprayout.SprayOutModel`; tests/formulate/test_closed_loop_simulator.py passes
the ma3 spectrophotometer simulator run as a subprocess (:func:`station.drivers.simproc.spawn_simulator`),
which shows an instrument can stand in for it.

Correction (additive offset per angle, the usual "batch correction"): with recipe r_n, prediction
P(r_n) and measurement M_n, the next recipe is formulated against the shifted target
T_{n+1} = design − (M_n − P(r_n)), starting from r_n. The model's systematic error is thus cancelled
to first order; it converges when that error varies slowly with the recipe.

Each step is a :class:`LoopStep` in a :class:`FormulationJob` (plain dataclasses: the database layer
stores them). Status: ``converged`` (mean measured ΔE00 ≤ tolerance), ``not_formulable`` (the model
cannot reach the design, nothing sprayed), or ``not_converged`` after ``max_corrections``.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.batch import Tinting, batch_masses, tinting_additions
from station.formulate.colorants import ColorantDatabase, default_database, predict_lab
from station.formulate.de_kernels import cie2000
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import DEFAULT_TOLERANCE, FormulationResult, formulate
from station.formulate.library import STANDARD_ANGLES
from station.formulate.snap import validate_design_lab
from station.model import AspecularMeasurements
from station.model.domain import LAB_HI, LAB_LO

Measure = Callable[[dict[str, float]], AspecularMeasurements]
MAX_CORRECTIONS = 3


@dataclass(frozen=True)
class LoopStep:
    """One spray-and-measure step.

    ``kind`` is ``"initial"`` or ``"correction"``; Lab arrays are (A, 3) at the job's angles;
    ``de_per_angle`` is the measured CIEDE2000 to the design; ``additions`` (corrections only) the
    tinting additions that turn the previous step's batch into this recipe.
    """

    number: int
    kind: str
    recipe: dict[str, float]
    target_lab: tuple[tuple[float, float, float], ...]
    predicted_lab: tuple[tuple[float, float, float], ...]
    measured_lab: tuple[tuple[float, float, float], ...]
    measured_gloss_gu: float | None
    de_per_angle: tuple[float, ...]
    mean_de: float
    predicted_mean_de: float
    time: str
    additions: Tinting | None = None

    def to_dict(self) -> dict[str, object]:
        """JSON-able form (``additions``: the tinting additions in g to a 1 kg batch, corrections only)."""
        out: dict[str, object] = {}
        for k, v in self.__dict__.items():
            if k == "additions":
                out[k] = None if v is None else v.to_dict()
            else:
                out[k] = list(v) if isinstance(v, tuple) else v
        out["batch"] = batch_masses(self.recipe).to_dict()
        return out


@dataclass(frozen=True)
class FormulationJob:
    """A formulation job and its history, in order (what the database stores)."""

    design_lab: tuple[tuple[float, float, float], ...]
    angles_deg: tuple[float, ...]
    gloss_gu: float | None
    tolerance: float
    status: str
    message: str
    steps: tuple[LoopStep, ...] = ()
    start: str = ""
    synthetic: bool = True
    initial: FormulationResult | None = field(default=None, compare=False, repr=False)

    @property
    def final_recipe(self) -> dict[str, float] | None:
        """Recipe of the last sprayed step (None when nothing was sprayed)."""
        return self.steps[-1].recipe if self.steps else None

    @property
    def corrections(self) -> int:
        """Number of correction steps taken."""
        return sum(1 for s in self.steps if s.kind == "correction")

    def to_dict(self) -> dict[str, object]:
        """JSON-able form."""
        return {
            "design_lab": [list(r) for r in self.design_lab],
            "angles_deg": list(self.angles_deg),
            "gloss_gu": self.gloss_gu,
            "tolerance": self.tolerance,
            "status": self.status,
            "message": self.message,
            "start": self.start,
            "corrections": self.corrections,
            "final_recipe": self.final_recipe,
            "steps": [s.to_dict() for s in self.steps],
            "synthetic_colorants": self.synthetic,
        }


def _tup(a: NDArray) -> tuple[tuple[float, float, float], ...]:
    return tuple((float(r[0]), float(r[1]), float(r[2])) for r in np.asarray(a))


def closed_loop(
    design_lab: ArrayLike,
    measure: Measure,
    angles_deg: tuple[float, ...] = STANDARD_ANGLES,
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None = None,
    gloss_gu: float | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    max_corrections: int = MAX_CORRECTIONS,
    db: ColorantDatabase | None = None,
) -> FormulationJob:
    """Formulate, spray, measure and correct until the panel is within *tolerance* (mean ΔE00).

    Parameters
    ----------
    design_lab
        Design Lab per angle, shape (A, 3) at *angles_deg*.
    measure
        ``measure(recipe) -> AspecularMeasurements`` at (a superset of) *angles_deg*.
    starts
        Starting recipes (e.g. ColorSnap matches' recipes), see :func:`formulate`.
    max_corrections
        Correction steps after the initial spray (0–10).
    """
    db = db or default_database()
    angles = tuple(float(a) for a in angles_deg)
    design = validate_design_lab(design_lab, len(angles), "design_lab")
    if not isinstance(max_corrections, int) or not 0 <= max_corrections <= 10:
        raise FormulateInputError("max_corrections", "an integer in [0, 10]", max_corrections)
    first = formulate(design, angles, starts, gloss_gu, tolerance, db)
    base = FormulationJob(
        design_lab=_tup(design),
        angles_deg=angles,
        gloss_gu=gloss_gu,
        tolerance=float(tolerance),
        status="",
        message="",
        start=first.start,
        synthetic=db.synthetic,
        initial=first,
    )
    if not first.formulable:
        return replace(base, status="not_formulable", message=first.message)
    steps: list[LoopStep] = []
    result = first
    target = design
    for n in range(max_corrections + 1):
        m = measure(dict(result.recipe))
        try:
            idx = [m.angles_deg.index(a) for a in angles]
        except ValueError as exc:
            raise FormulateInputError(
                "measurement.angles_deg", f"a superset of {angles}", m.angles_deg
            ) from exc
        measured = np.asarray(m.lab)[idx]
        de = cie2000(design, measured)
        predicted = predict_lab(result.concentrations, angles, db)
        steps.append(
            LoopStep(
                number=n,
                kind="initial" if n == 0 else "correction",
                recipe=dict(result.recipe),
                target_lab=_tup(target),
                predicted_lab=_tup(predicted),
                measured_lab=_tup(measured),
                measured_gloss_gu=m.gloss_gu,
                de_per_angle=tuple(float(v) for v in de),
                mean_de=float(de.mean()),
                predicted_mean_de=result.mean_de,
                time=dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
                additions=None if n == 0 else tinting_additions(steps[-1].recipe, dict(result.recipe)),
            )
        )
        if de.mean() <= tolerance:
            msg = f"converged: mean ΔE00 {de.mean():.2f} after {n} correction(s)"
            return replace(base, status="converged", message=msg, steps=tuple(steps))
        if n == max_corrections:
            break
        target = design - (measured - predicted)
        target = np.clip(target, LAB_LO, LAB_HI)  # a corrected target stays inside the domain's Lab bound
        result = formulate(target, angles, [("previous", result.concentrations)], gloss_gu, 1e9, db)
    msg = f"not converged: mean ΔE00 {steps[-1].mean_de:.2f} after {max_corrections} correction(s)"
    if len(steps) > 1 and steps[-1].predicted_mean_de > tolerance:
        msg += (
            f"; the corrected target is out of the model's reach (predicted ΔE00 {steps[-1].predicted_mean_de:.2f}):"
            " the design is likely outside the gamut of the colorants actually sprayed"
        )
    return replace(base, status="not_converged", message=msg, steps=tuple(steps))
