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
P(r_n) and measurement M_n, the corrected target is T_{n+1} = design − (M_n − P(r_n)). The model's
systematic error is thus cancelled to first order; it converges when that error varies slowly with the
recipe. The correction is made as the lab makes it, by **tinting** (:mod:`station.formulate.tinting`):
additions of the recipe's own colorants and binder to the batch already mixed, rounded to the scale,
within the batch's bounds. When no such additions reach T within the tolerance but a new recipe does,
the step says "remake" and gives the new recipe (a fresh batch), never impossible additions.

The measured offset M_n − P(r_n) belongs to the colorants in the can: the model's error differs from
colorant to colorant (an interference pigment's spectral albedo, a red's strength), so a recipe of other
colorants has another offset. When neither tinting nor a remake of the same colorants is predicted to
reach the corrected target (the offset cannot be cancelled with these colorants), the loop remakes with a
colorant set not sprayed yet: of the toner line's recipes for the design itself within the tolerance (a
wider search, :data:`OTHER_SET_CANDIDATES` starts), the one sharing the fewest colorants with those
already sprayed (then the best ranked), and corrects that one from its own spray-out.

:func:`correct_batch` is one such correction on its own, for a batch sprayed and measured outside the
loop (``station tint``).

Each step is a :class:`LoopStep` in a :class:`FormulationJob` (plain dataclasses: the database layer
stores them). Status: ``converged`` (mean measured ΔE00 ≤ tolerance), ``not_formulable`` (the model
cannot reach the design, nothing sprayed), or ``not_converged`` after ``max_corrections``. The job's
``warnings`` name every angle that ends worse than the tolerance or worse than at the first spray-out.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.batch import DEFAULT_BATCH_G, Tinting, batch_masses
from station.formulate.colorants import ColorantDatabase, default_database, predict_lab
from station.formulate.de_kernels import cie2000
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import (
    DEFAULT_TOLERANCE,
    FormulationOptions,
    FormulationResult,
    formulate_with,
)
from station.formulate.library import STANDARD_ANGLES
from station.formulate.lines import toner_line
from station.formulate.selection import RecipeOption
from station.formulate.snap import validate_design_lab
from station.formulate.tinting import tint
from station.model import AspecularMeasurements
from station.model.domain import LAB_HI, LAB_LO, aspecular_name
from station.wire import wire_form

Measure = Callable[[dict[str, float]], AspecularMeasurements]
Starts = list[tuple[str, ArrayLike | dict[str, float]]]
MAX_CORRECTIONS = 3
#: Starts fitted (at least) when the loop looks for another colorant set (see :func:`_other_colorants`).
OTHER_SET_CANDIDATES = 8
#: Recipes of distinct colorant sets ranked in that search.
OTHER_SET_RECIPES = 8


@dataclass(frozen=True)
class LoopStep:
    """One spray-and-measure step.

    ``kind`` is ``"initial"`` or ``"correction"``; Lab arrays are (A, 3) at the job's angles;
    ``de_per_angle`` is the measured CIEDE2000 to the design; ``additions`` (corrections only) the
    tinting additions (g) that turn the previous step's batch into this recipe, or, with
    ``additions.remake``, the notice that this recipe is a fresh batch; ``batch_g`` the batch's mass.
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
    batch_g: float = DEFAULT_BATCH_G

    def to_dict(self) -> dict[str, object]:
        """JSON-able form (``additions``: the tinting additions in g to the batch, corrections only)."""
        return wire_form(self, after={"batch_g": {"batch": batch_masses(self.recipe, self.batch_g)}})


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
    warnings: tuple[str, ...] = ()

    @property
    def final_recipe(self) -> dict[str, float] | None:
        """Recipe of the last sprayed step (None when nothing was sprayed)."""
        return self.steps[-1].recipe if self.steps else None

    @property
    def corrections(self) -> int:
        """Number of correction steps taken."""
        return sum(1 for s in self.steps if s.kind == "correction")

    def to_dict(self) -> dict[str, object]:
        """JSON-able form (the steps after the corrections' count and the final recipe; not the initial
        formulation)."""
        return wire_form(
            self,
            rename={"synthetic": "synthetic_colorants"},
            omit={"steps", "initial"},
            after={
                "start": {
                    "corrections": self.corrections,
                    "final_recipe": self.final_recipe,
                    "steps": self.steps,
                }
            },
        )


def _tup(a: NDArray) -> tuple[tuple[float, float, float], ...]:
    return tuple((float(r[0]), float(r[1]), float(r[2])) for r in np.asarray(a))


@dataclass
class _Batch:
    """The batch in the can: grams per colorant (database order), binder (g), its recipe and prediction;
    ``result`` the formulation it was weighed out from (None once tinted) and ``line`` the toner line
    it was mixed from (kept through tinting: a remake stays with the line sprayed)."""

    masses: NDArray[np.float64]
    binder: float
    result: FormulationResult | None
    concentrations: NDArray[np.float64]
    predicted_mean_de: float
    line: str | None = None

    @property
    def total(self) -> float:
        return float(self.masses.sum() + self.binder)


def _fresh(result: FormulationResult, batch_g: float) -> _Batch:
    c = np.asarray(result.concentrations, dtype=np.float64)
    return _Batch(
        c * batch_g, float((1.0 - c.sum()) * batch_g), result, c, result.mean_de, result.line or None
    )


def _measure(measure: Measure, recipe: dict[str, float], angles: tuple[float, ...]) -> AspecularMeasurements:
    m = measure(recipe)
    if any(a not in m.angles_deg for a in angles):
        raise FormulateInputError("measurement.angles_deg", f"a superset of {angles}", m.angles_deg)
    return m


def closed_loop(
    design_lab: ArrayLike,
    measure: Measure,
    angles_deg: tuple[float, ...] = STANDARD_ANGLES,
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None = None,
    gloss_gu: float | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    max_corrections: int = MAX_CORRECTIONS,
    db: ColorantDatabase | None = None,
    options: FormulationOptions | None = None,
) -> FormulationJob:
    """Formulate, spray, measure and correct by tinting until the panel is within *tolerance*.

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
    options
        The chemist's limits (toner line, colorants, scale, batch), :class:`FormulationOptions`.
    """
    db = db or default_database()
    angles = tuple(float(a) for a in angles_deg)
    design = validate_design_lab(design_lab, len(angles), "design_lab")
    if not isinstance(max_corrections, int) or not 0 <= max_corrections <= 10:
        raise FormulateInputError("max_corrections", "an integer in [0, 10]", max_corrections)
    opts = options or FormulationOptions()
    first = formulate_with(design, angles, starts, gloss_gu, tolerance, db, opts)
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
    steps = _run(
        design, angles, measure, first, float(tolerance), max_corrections, db, opts, gloss_gu, starts
    )
    last = steps[-1]
    if last.mean_de <= tolerance:
        status, msg = (
            "converged",
            f"converged: mean ΔE00 {last.mean_de:.2f} after {len(steps) - 1} correction(s)",
        )
    else:
        status = "not_converged"
        msg = f"not converged: mean ΔE00 {last.mean_de:.2f} after {max_corrections} correction(s)"
        if len(steps) > 1 and last.predicted_mean_de > tolerance:
            msg += (
                f"; the corrected target is out of the model's reach (predicted ΔE00 {last.predicted_mean_de:.2f}):"
                " the design is likely outside the gamut of the colorants actually sprayed"
            )
    return replace(
        base,
        status=status,
        message=msg,
        steps=tuple(steps),
        warnings=_angle_warnings(steps, angles, tolerance),
    )


def _run(
    design: NDArray,
    angles: tuple[float, ...],
    measure: Measure,
    first: FormulationResult,
    tolerance: float,
    max_corrections: int,
    db: ColorantDatabase,
    opts: FormulationOptions,
    gloss_gu: float | None,
    starts: Starts | None,
) -> list[LoopStep]:
    """Spray, measure, correct: the steps until converged or out of corrections."""
    batch = _fresh(first, opts.batch_g)
    steps: list[LoopStep] = []
    sprayed: set[frozenset[str]] = set()
    target = design
    additions: Tinting | None = None
    for n in range(max_corrections + 1):
        recipe = db.recipe(batch.concentrations, 1e-9)
        sprayed.add(_colorant_set(recipe, db))
        m = _measure(measure, dict(recipe), angles)
        measured = np.asarray(m.lab)[[m.angles_deg.index(a) for a in angles]]
        de = cie2000(design, measured)
        predicted = predict_lab(batch.concentrations, angles, db)
        steps.append(
            LoopStep(
                number=n,
                kind="initial" if n == 0 else "correction",
                recipe=recipe,
                target_lab=_tup(target),
                predicted_lab=_tup(predicted),
                measured_lab=_tup(measured),
                measured_gloss_gu=m.gloss_gu,
                de_per_angle=tuple(float(v) for v in de),
                mean_de=float(de.mean()),
                predicted_mean_de=batch.predicted_mean_de,
                time=dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
                additions=additions,
                batch_g=batch.total,
            )
        )
        if de.mean() <= tolerance or n == max_corrections:
            break
        target = np.clip(design - (measured - predicted), LAB_LO, LAB_HI)  # stays inside the Lab bound
        batch, additions = _correct(batch, target, angles, tolerance, db, opts, gloss_gu)
        if additions.remake and batch.predicted_mean_de > tolerance:  # out of reach with these colorants
            other = _other_colorants(design, angles, starts, batch, sprayed, tolerance, db, opts, gloss_gu)
            if other is not None:
                (batch, additions), target = other, design  # formulated for the design itself
    return steps


def _colorant_set(recipe: dict[str, float], db: ColorantDatabase) -> frozenset[str]:
    """The colorants of a recipe (binder and matting agent not counted)."""
    extra = {db.names[db.matting_index]}
    return frozenset(k for k, v in recipe.items() if v > 0 and k not in extra)


def _other_colorants(
    design: NDArray,
    angles: tuple[float, ...],
    starts: Starts | None,
    batch: _Batch,
    sprayed: set[frozenset[str]],
    tolerance: float,
    db: ColorantDatabase,
    opts: FormulationOptions,
    gloss_gu: float | None,
) -> tuple[_Batch, Tinting] | None:
    """A fresh batch of a colorant set not sprayed yet, formulated for the design (module docstring),
    or ``None`` when the toner line has no such recipe within the tolerance."""
    wide = replace(opts, line=opts.line or batch.line, recipes=OTHER_SET_RECIPES)
    found = formulate_with(
        design,
        angles,
        [("previous", batch.concentrations), *(starts or [])],
        gloss_gu,
        1e9,
        db,
        wide,
        OTHER_SET_CANDIDATES,
    )
    used = frozenset().union(*sprayed)

    def shared(option: RecipeOption) -> int:  # colorants it shares with those already sprayed
        return len(_colorant_set(option.recipe, db) & used)

    for option in sorted(found.recipes, key=lambda o: (shared(o), o.rank)):
        colorants = _colorant_set(option.recipe, db)
        if option.mean_de <= tolerance and colorants not in sprayed:
            c = np.asarray(option.concentrations, dtype=np.float64)
            fresh = _Batch(
                c * opts.batch_g,
                float((1.0 - c.sum()) * opts.batch_g),
                found,
                c,
                option.mean_de,
                option.line or None,
            )
            note = Tinting(
                {},
                0.0,
                opts.batch_g,
                True,
                f"remake with other colorants ({', '.join(sorted(colorants))}): with the colorants sprayed "
                f"the corrected target stays out of reach (predicted ΔE00 {batch.predicted_mean_de:.2f}); "
                f"the new recipe reaches {option.mean_de:.2f} on the design in a fresh {opts.batch_g:g} g batch",
            )
            return fresh, note
    return None


def _correct(
    batch: _Batch,
    target: NDArray,
    angles: tuple[float, ...],
    tolerance: float,
    db: ColorantDatabase,
    opts: FormulationOptions,
    gloss_gu: float | None,
) -> tuple[_Batch, Tinting]:
    """Tint the batch toward *target*; remake (a new recipe, a fresh batch) only when tinting cannot
    reach the tolerance and the new recipe can, or does better."""
    batch_g = opts.batch_g
    t = tint(batch.masses, batch.binder, target, angles, db, opts.scale_resolution_g, batch_g)
    tinted = _Batch(t.masses_g, t.binder_g, None, t.concentrations, t.predicted_mean_de, batch.line)
    if t.predicted_mean_de <= tolerance:
        return tinted, t.tinting
    start: list[tuple[str, ArrayLike | dict[str, float]]] = [("previous", batch.concentrations)]
    remade = formulate_with(
        target, angles, start, gloss_gu, 1e9, db, replace(opts, line=opts.line or batch.line)
    )
    if remade.mean_de < t.predicted_mean_de:
        note = Tinting(
            {},
            0.0,
            batch_g,
            True,
            f"remake the batch: additions reach only ΔE00 {t.predicted_mean_de:.2f} (predicted) within "
            f"the batch's bounds; the new recipe reaches {remade.mean_de:.2f} in a fresh {batch_g:g} g batch",
        )
        return _fresh(remade, batch_g), note
    return tinted, t.tinting


@dataclass(frozen=True)
class BatchCorrection:
    """One correction of a sprayed and measured batch (:func:`correct_batch`).

    ``target_lab`` the corrected target T = design − (measured − predicted), (A, 3); ``measured_de`` the
    measured panel's CIEDE2000 to the design per angle; ``tinting`` the additions (g) to the batch in the
    can, or with ``tinting.remake`` the notice that a fresh batch of ``recipe`` is needed; ``recipe`` the
    mass fractions after the correction; ``masses_g`` (colorants) and ``binder_g`` the batch after it (g);
    ``predicted_lab`` the colorant model's prediction of ``recipe`` and ``predicted_mean_de`` its mean
    CIEDE2000 to ``target_lab``: the mean ΔE00 to the design the next panel is predicted to read, since the
    measured offset is carried over to it.
    """

    angles_deg: tuple[float, ...]
    target_lab: tuple[tuple[float, float, float], ...]
    measured_de: tuple[float, ...]
    measured_mean_de: float
    tinting: Tinting
    recipe: dict[str, float]
    masses_g: dict[str, float]
    binder_g: float
    predicted_lab: tuple[tuple[float, float, float], ...]
    predicted_mean_de: float

    def to_dict(self) -> dict[str, object]:
        """JSON-able form (``tinting`` as :meth:`Tinting.to_dict`)."""
        return wire_form(self)


def _batch_in_can(masses_g: dict[str, float], binder_g: float, db: ColorantDatabase) -> NDArray[np.float64]:
    """The can's grams per colorant in database order, each checked (field ``batch.colorants_g.NAME``,
    ``batch.binder_g``)."""
    m = np.zeros(len(db.names))
    for name, grams in masses_g.items():
        if name not in db.names:
            raise FormulateInputError(f"batch.colorants_g.{name}", f"a colorant of {db.names}", name)
        if (
            isinstance(grams, bool)
            or not isinstance(grams, int | float)
            or not np.isfinite(grams)
            or grams < 0
        ):
            raise FormulateInputError(f"batch.colorants_g.{name}", "a finite mass >= 0 g", grams)
        m[db.names.index(name)] = float(grams)
    if isinstance(binder_g, bool) or not isinstance(binder_g, int | float) or not np.isfinite(binder_g):
        raise FormulateInputError("batch.binder_g", "a finite mass > 0 g", binder_g)
    if binder_g <= 0 or not np.any(m > 0):
        raise FormulateInputError("batch", "colorants and binder with masses > 0 g", {**masses_g})
    return m


def correct_batch(
    design_lab: ArrayLike,
    measured_lab: ArrayLike,
    masses_g: dict[str, float],
    binder_g: float,
    angles_deg: tuple[float, ...] = STANDARD_ANGLES,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
    options: FormulationOptions | None = None,
    gloss_gu: float | None = None,
) -> BatchCorrection:
    """Correct a sprayed batch from its measured panel, as one step of :func:`closed_loop` does.

    Parameters
    ----------
    design_lab, measured_lab
        Design and measured panel, Lab per angle, shape (A, 3) at *angles_deg* (degrees, aspecular).
    masses_g, binder_g
        The batch in the can: grams per colorant (matting agent included) and of binder.
    tolerance
        Mean ΔE00 the correction aims within: a panel within it gets no additions; a remake is advised
        only when additions cannot reach it and a new recipe can, or does better. Neither additions
        nor a remake is given when not predicted to improve the panel.
    options
        The chemist's limits: ``line`` (every colorant of the batch must belong to it), the scale's
        ``scale_resolution_g`` (additions rounded to it) and ``batch_g`` (the first batch: tinting
        may grow it to :data:`~station.formulate.batch.MAX_GROWTH` times).

    Raises
    ------
    FormulateInputError
        Naming the field: ``design_lab``/``measured_lab`` (shape, range), ``batch.*`` (masses),
        ``recipe.NAME`` (a colorant outside the options' toner line).
    """
    db = db or default_database()
    angles = tuple(float(a) for a in angles_deg)
    design = validate_design_lab(design_lab, len(angles), "design_lab")
    measured = validate_design_lab(measured_lab, len(angles), "measured_lab")
    opts = options or FormulationOptions()
    m = _batch_in_can(masses_g, binder_g, db)
    if opts.line is not None:
        allowed = toner_line(opts.line).mask(db)
        for i in np.flatnonzero(m > 0):
            if not allowed[i] and i != db.matting_index:
                raise FormulateInputError(
                    f"recipe.{db.names[i]}", f"a colorant of the {opts.line} toner line", db.names[i]
                )
    c0 = m / float(m.sum() + binder_g)
    predicted = predict_lab(c0, angles, db)
    target = np.clip(design - (measured - predicted), LAB_LO, LAB_HI)
    de = cie2000(design, measured)
    now = float(cie2000(target, predicted).mean())  # what the next panel reads with nothing added
    batch = _Batch(m, float(binder_g), None, c0, now, opts.line)
    total = float(m.sum() + binder_g)
    if de.mean() <= tolerance:
        after = batch
        tinting = Tinting({}, 0.0, total, False, f"within the tolerance {tolerance:g}: nothing to add")
    else:
        after, tinting = _correct(batch, target, angles, float(tolerance), db, opts, gloss_gu)
        if after.predicted_mean_de >= now:
            after = batch
            tinting = Tinting(
                {},
                0.0,
                total,
                False,
                f"neither additions nor a remake are predicted to improve the panel (ΔE00 {now:.2f})",
            )
    return BatchCorrection(
        angles_deg=angles,
        target_lab=_tup(target),
        measured_de=tuple(float(v) for v in de),
        measured_mean_de=float(de.mean()),
        tinting=tinting,
        recipe=db.recipe(after.concentrations, 1e-9),
        masses_g={n: float(g) for n, g in zip(db.names, after.masses, strict=True) if g > 0},
        binder_g=float(after.binder),
        predicted_lab=_tup(predict_lab(after.concentrations, angles, db)),
        predicted_mean_de=float(after.predicted_mean_de),
    )


def _angle_warnings(steps: list[LoopStep], angles: tuple[float, ...], tolerance: float) -> tuple[str, ...]:
    """A warning for every angle of the last step worse than the tolerance or than the first spray-out."""
    first, last = steps[0], steps[-1]
    out = []
    for a, d0, d1 in zip(angles, first.de_per_angle, last.de_per_angle, strict=True):
        if d1 > tolerance:
            out.append(f"{aspecular_name(a)} ends at ΔE00 {d1:.2f}, worse than the tolerance {tolerance:g}")
        if len(steps) > 1 and d1 > d0:
            out.append(
                f"{aspecular_name(a)} ends at ΔE00 {d1:.2f}, worse than the first spray-out's {d0:.2f}"
            )
    return tuple(out)
