"""Formulation on designs the colorant model did not make: gamut check, first-shot recipe, size, time.

The designs (seeded, 310 in all) are what a stylist, a QA engineer or a thesis figure hands the chemist,
not predictions of the colorant model's own recipes:

* **stylist edits** (100): demo-library paints (fitted to face/flop/travel/gloss) with a hue/saturation/
  brightness move (hue ±5–20°, chroma ×0.85–1.15, L* ±2–6) or a face or flop move of 2–6 ΔE*ab;
* **QA-corrected paints** (60): demo-library paints "measured" at 15/25/45/75/110° with instrument-size
  noise (σ 0.3 in L*, a*, b*) and fitted to face/flop/travel/gloss, the form QA hands over;
* **bright silvers** (40): face L* 110–140, flop L* 25–45, near-neutral, travel 55–95°;
* **thesis and documentation designs** (10): the model examples, the analysis scenarios (Fig 4.6
  bumper blue), the README silver and the viewer's red;
* **smooth perturbations** (100): demo-library paints plus a perturbation quadratic in the angle
  (up to 2.5 per channel), fitted to face/flop/travel/gloss.

Each design goes through the gamut check — the physical bound
(:func:`station.analysis.gamut.check_paintable`: sRGB chromaticity, reflectance), the toner line's
gamut (every colorant of the line, amounts unrounded) and the N-colorant gamut
(:func:`station.formulate.gamut.recipe_gamut`: a recipe of at most N = 5 colorants of the line, the
selection's subset screen and a continuous refit of its best subsets; it does not run the formulation),
from the same ColorSnap starts and on the same line as the formulation — then
:func:`station.formulate.formulation.formulate_from_library` with the demo library and the default
limits (toner line from the type, at most 5 colorants, amounts rounded to 0.1 g per 1000 g). Per set:
how many designs each step of the gamut check accepts; of the N-colorant gamut's accepts, the share
within mean ΔE00 ≤ 1.0 at 15/45/110° first shot with a weighable recipe (every amount a multiple of the
resolution, bar ≥ 95 %), and the same share among the line's gamut's accepts (the figure before the
colorant limit); the median number of colorants; the median formulation time, process CPU and wall
clock (bar ≤ 1 s), and of formulation plus N-colorant check; the 1-minute load average. Designs a gamut
refuses are formulated too, to count any the formulation reaches anyway. The N-colorant verdict is
compared with a brute force (:func:`exhaustive_best`: every 5-subset of each line the design's type may
use, screened, the 25 best refitted and refined) on every miss, every N-colorant refusal and a seeded
quarter of the accepts: false accepts and false refusals are counted and listed. Baseline, same run:
20 designs the colorant model did make (predictions of generator recipes), through the same steps.

Run: ``nice python -m bench.formulate_independent`` (ten minutes or more on a loaded machine);
``--quick``: every fourth design of each set (all thesis designs), nothing written.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

import numpy as np

from bench._report import Case, write_section
from station.analysis.gamut import check_paintable
from station.analysis.scenarios import BUMPER_PAINT, SILVER_PAINT, SOLID_PAINT
from station.formulate.colorants import default_database, predict_lab
from station.formulate.de_kernels import cie2000
from station.formulate.demo import demo_library, generate_recipes
from station.formulate.formulation import (
    MAX_STARTS,
    formulate_from_library,
    library_starts,
    line_wide_fit,
    matting_for_gloss,
)
from station.formulate.gamut import recipe_gamut
from station.formulate.library import Library
from station.formulate.lines import lines_for_design
from station.formulate.selection import fit_subset, refine_subset, screen
from station.formulate.snap import SnapIndex
from station.model import AspecularMeasurements, FaceFlopTravelGloss
from station.model.domain import DEFAULT_MAX_COLORANTS, FORMULATION_TOLERANCE_DE00
from station.model.examples import BRIGHT_SILVER, HUE_SHIFT_PEARL, RED_METALLIC, SILVER, SOLID_WHITE
from station.model.fit import fit_fftg

A3 = (15.0, 45.0, 110.0)
SEED = 2025
RESOLUTION_G = 0.1
TOLERANCE = FORMULATION_TOLERANCE_DE00
MAX_COLORANTS = DEFAULT_MAX_COLORANTS
#: Share of the accepted designs (seeded draw) checked against brute force besides misses and refusals.
BRUTE_SAMPLE = 0.25
README_SILVER = np.array([[90.0, 2.0, -5.0], [50.0, 1.0, -3.0], [30.0, 0.5, -1.0]])
VIEWER_RED = FaceFlopTravelGloss((62.0, 48.0, 30.0), (24.0, 38.0, 18.0), 70.0, 88.0, "viewer red")


def _fit(angles: tuple[float, ...], lab: np.ndarray, gloss: float) -> FaceFlopTravelGloss:
    order = np.argsort(angles)
    sorted_angles = tuple(float(angles[k]) for k in order)
    lab_sorted = np.asarray(lab, dtype=float)[order]
    return fit_fftg(AspecularMeasurements(sorted_angles, lab_sorted, float(gloss))).design


def _paint(lib: Library, i: int) -> FaceFlopTravelGloss:
    return _fit(tuple(lib.angles_deg), lib.lab[i], float(lib.gloss_gu[i]))


def _lch_move(lab: tuple[float, float, float], dl: float, cf: float, dh: float) -> tuple[float, float, float]:
    c, h = np.hypot(lab[1], lab[2]) * cf, np.arctan2(lab[2], lab[1]) + np.radians(dh)
    return (float(np.clip(lab[0] + dl, 1.0, 140.0)), float(c * np.cos(h)), float(c * np.sin(h)))


def stylist(lib: Library, rng: np.random.Generator, n: int) -> list[FaceFlopTravelGloss]:
    out = []
    for k, i in enumerate(rng.choice(len(lib), n, replace=False)):
        p = _paint(lib, int(i))
        if k % 2 == 0:  # hue / saturation / brightness
            dl, cf, dh = (
                rng.choice([-1, 1]) * rng.uniform(2, 6),
                rng.uniform(0.85, 1.15),
                rng.choice([-1, 1]) * rng.uniform(5, 20),
            )
            face, flop = _lch_move(p.face, dl, cf, dh), _lch_move(p.flop, dl, cf, dh)
        else:  # a face or a flop move of 2–6 ΔE*ab
            v = rng.normal(size=3)
            v *= rng.uniform(2, 6) / np.linalg.norm(v)
            face = tuple(np.add(p.face, v if k % 4 == 1 else 0.0).tolist())
            flop = tuple(np.add(p.flop, v if k % 4 == 3 else 0.0).tolist())
        if p.travel_deg is None:  # a solid stays a solid: its one colour moves
            flop = face = face if k % 4 != 3 else flop
        out.append(FaceFlopTravelGloss(face, flop, p.travel_deg, p.gloss_gu, "stylist edit"))
    return out


def qa_corrected(lib: Library, rng: np.random.Generator, n: int) -> list[FaceFlopTravelGloss]:
    idx = rng.choice(len(lib), n, replace=False)
    return [
        _fit(tuple(lib.angles_deg), lib.lab[i] + rng.normal(0, 0.3, lib.lab[i].shape), float(lib.gloss_gu[i]))
        for i in idx
    ]


def bright_silvers(rng: np.random.Generator, n: int) -> list[FaceFlopTravelGloss]:
    return [
        FaceFlopTravelGloss(
            (rng.uniform(110, 140), rng.uniform(-1, 1), rng.uniform(-3, 1)),
            (rng.uniform(25, 45), rng.uniform(-1, 1), rng.uniform(-4, 0)),
            rng.uniform(55, 95),
            90.0,
            "bright silver",
        )
        for _ in range(n)
    ]


def thesis_designs() -> list[FaceFlopTravelGloss]:
    readme = _fit(A3, README_SILVER, 90.0)
    return [
        SOLID_WHITE,
        SILVER,
        RED_METALLIC,
        HUE_SHIFT_PEARL,
        BRIGHT_SILVER,
        SOLID_PAINT,
        SILVER_PAINT,
        BUMPER_PAINT,
        readme,
        VIEWER_RED,
    ]


def perturbed(lib: Library, rng: np.random.Generator, n: int) -> list[FaceFlopTravelGloss]:
    t = (np.asarray(lib.angles_deg) - 45.0) / 65.0
    out = []
    for i in rng.choice(len(lib), n, replace=False):
        coef = rng.uniform(-2.5, 2.5, size=(3, 3)) / 2.0  # p0 + p1 t + p2 t², per channel
        delta = coef[0] + np.outer(t, coef[1]) + np.outer(t * t, coef[2])
        out.append(_fit(tuple(lib.angles_deg), lib.lab[i] + delta, float(lib.gloss_gu[i])))
    return out


def model_made(n: int) -> list[tuple[np.ndarray, float]]:
    _, c = generate_recipes(n // 3 + n % 3, n // 3, n // 3, seed=777)
    return [(predict_lab(ci, A3), 90.0) for ci in c]


@dataclass
class SetResult:
    name: str
    designs: int
    physical: int = 0
    accepted: int = 0  # the line's gamut (every colorant free)
    first_shot: int = 0  # among the line's gamut's accepts (the figure before the colorant limit)
    recipe_accepted: int = 0  # the N-colorant gamut
    recipe_first_shot: int = 0  # among the N-colorant gamut's accepts
    sizes: list[int] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    cpu: list[float] = field(default_factory=list)
    check_times: list[float] = field(default_factory=list)
    check_cpu: list[float] = field(default_factory=list)
    refused_reached: int = 0
    recipe_refused_reached: int = 0
    beyond_five: int = 0
    loads: list[float] = field(default_factory=list)
    brute: list[Verdict] = field(default_factory=list)


@dataclass(frozen=True)
class Verdict:
    """The N-colorant gamut's verdict on one design beside the brute-force best of every N-subset."""

    set_name: str
    design: int
    inside: bool
    screen_de: float
    brute_de: float

    @property
    def false_accept(self) -> bool:
        return self.inside and self.brute_de > TOLERANCE

    @property
    def false_refusal(self) -> bool:
        return not self.inside and self.brute_de <= TOLERANCE


def exhaustive_best(lab: np.ndarray, gloss: float, line: str, max_colorants: int = MAX_COLORANTS) -> float:
    """Best mean ΔE00 (unrounded) of any recipe of at most *max_colorants* colorants of *line*: every
    subset of the line screened (:func:`station.formulate.selection.screen` without its limit), the 25
    best refitted and refined — the brute-force check of a miss and of the N-colorant gamut."""
    db = default_database()
    c_mat = matting_for_gloss(gloss, db)[0]
    prob, _, tried = line_wide_fit(lab, A3, [], c_mat, db, line, MAX_STARTS, TOLERANCE)
    best = np.inf
    for sub, x0 in screen(prob, tried[0][2], max_colorants, keep=25, limit=10**6):
        _, x, obj = fit_subset(prob, sub, x0)
        c = refine_subset(obj, x, 1e-6)
        best = min(best, float(cie2000(lab, predict_lab(c, A3, db)).mean()))
    return best


def _weighable(grams: dict[str, float]) -> bool:
    return all(
        g >= RESOLUTION_G - 1e-9 and abs(g / RESOLUTION_G - round(g / RESOLUTION_G)) < 1e-6
        for g in grams.values()
    )


def _brute_lines(paint_type: str | None, lab: np.ndarray) -> tuple[str, ...]:
    """Every line the N-colorant gamut may try for the design (the brute force runs on each; the best
    counts)."""
    return lines_for_design(lab, None, paint_type)


def run_set(
    name: str,
    designs: list[tuple[np.ndarray, float]],
    physical: list[bool],
    lib: Library,
    index: SnapIndex,
    sample: np.random.Generator,
) -> SetResult:
    res = SetResult(name, len(designs))
    for k, (lab, gloss) in enumerate(designs):
        if not physical[k]:
            continue
        res.physical += 1
        starts, opts, _ = library_starts(lab, lib, index)
        t0, c0 = time.perf_counter(), time.process_time()
        gamut = recipe_gamut(
            lab, A3, gloss, max_colorants=MAX_COLORANTS, paint_type=opts.paint_type, starts=starts
        )
        gt, gc = time.perf_counter() - t0, time.process_time() - c0
        t0, c0 = time.perf_counter(), time.process_time()
        r, _ = formulate_from_library(lab, lib, index, gloss_gu=gloss)
        dt, dc = time.perf_counter() - t0, time.process_time() - c0
        res.loads.append(os.getloadavg()[0])
        hit = r.formulable and _weighable(r.recipes[0].grams)
        if not gamut.line_inside:
            res.refused_reached += int(hit)
            print(f"  {name} {k + 1}/{len(designs)}: {gamut.message}", flush=True)
            continue
        res.accepted += 1
        res.first_shot += int(hit)
        res.times.append(dt)
        res.cpu.append(dc)
        res.check_times.append(gt)
        res.check_cpu.append(gc)
        res.sizes.append(r.recipes[0].colorants)
        brute = np.nan
        # brute force: every miss, every N-colorant refusal, and a seeded sample of one in four accepts
        if not hit or not gamut.inside or sample.random() < BRUTE_SAMPLE:
            brute = min(exhaustive_best(lab, gloss, ln) for ln in _brute_lines(opts.paint_type, lab))
            res.brute.append(Verdict(name, k, gamut.inside, gamut.mean_de, brute))
            if not hit and brute > TOLERANCE:
                res.beyond_five += 1
        if gamut.inside:
            res.recipe_accepted += 1
            res.recipe_first_shot += int(hit)
        else:
            res.recipe_refused_reached += int(hit)
        print(
            f"  {name} {k + 1}/{len(designs)}: {r.mean_de:.2f} {dc:.2f} s CPU + check {gc:.2f} s; "
            f"{gamut.message}; brute force {brute:.2f}",
            flush=True,
        )
    print(
        f"{name}: {res.recipe_first_shot}/{res.recipe_accepted} ({res.first_shot}/{res.accepted})", flush=True
    )
    return res


def _median(v: list[float] | list[int]) -> float:
    return float(np.median(v)) if v else float("nan")


def _cases(r: SetResult, base_time: float) -> list[Case]:
    share = 100.0 * r.recipe_first_shot / max(r.recipe_accepted, 1)
    old = 100.0 * r.first_shot / max(r.accepted, 1)
    t, cpu = _median(r.times), _median(r.cpu)
    both_cpu = _median([a + b for a, b in zip(r.cpu, r.check_cpu, strict=True)])
    both_wall = _median([a + b for a, b in zip(r.times, r.check_times, strict=True)])
    fa = sum(v.false_accept for v in r.brute)
    fr = sum(v.false_refusal for v in r.brute)
    note = (
        f"accepts: physical bound {r.physical}/{r.designs}, line's gamut {r.accepted}, "
        f"{MAX_COLORANTS}-colorant gamut {r.recipe_accepted}; first shot {r.recipe_first_shot}/"
        f"{r.recipe_accepted} of the {MAX_COLORANTS}-colorant gamut's accepts "
        f"({'meets' if share >= 95 else 'misses'} the 95 % bar); before the colorant limit "
        f"{r.first_shot}/{r.accepted} of the line's gamut's accepts ({old:.1f} %); formulated although "
        f"refused: by the line's gamut {r.refused_reached}, by the {MAX_COLORANTS}-colorant gamut "
        f"{r.recipe_refused_reached}; misses with no recipe of ≤ {MAX_COLORANTS} colorants within 1.0 by "
        f"brute force {r.beyond_five}; {MAX_COLORANTS}-colorant gamut against brute force on "
        f"{len(r.brute)} designs: {fa} false accepts, {fr} false refusals; median {_median(r.sizes):g} "
        f"colorants; formulation median {cpu:.2f} s CPU, {t:.2f} s wall "
        f"({'meets' if t <= 1.0 else 'misses'} the 1 s bar in wall, {'meets' if cpu <= 1.0 else 'misses'} "
        f"it in CPU; {t / base_time:.2f}× the model-made baseline's wall); formulation + "
        f"{MAX_COLORANTS}-colorant gamut check median {both_cpu:.2f} s CPU, {both_wall:.2f} s wall; "
        f"load average (1 min) median {_median(r.loads):.1f}, max {max(r.loads, default=float('nan')):.1f}"
    )
    return [Case(f"independent: {r.name}", f"{r.designs} designs", share, "% first shot", note)]


def run(quick: bool = False) -> None:
    rng = np.random.default_rng(SEED)
    lib = demo_library()
    index = SnapIndex(lib)
    made = {  # drawn in this order whatever order they run in (the seed's stream)
        "stylist edits": stylist(lib, rng, 100),
        "QA-corrected paints": qa_corrected(lib, rng, 60),
        "bright silvers": bright_silvers(rng, 40),
        "thesis and documentation designs": thesis_designs(),
        "smooth perturbations": perturbed(lib, rng, 100),
    }
    order = ("thesis and documentation designs", "bright silvers", "QA-corrected paints", "stylist edits")
    sets = {name: made[name] for name in (*order, "smooth perturbations")}
    if quick:
        sets = {n: p if n == order[0] else p[::4] for n, p in sets.items()}
    made_designs = model_made(8 if quick else 20)
    sample = np.random.default_rng(SEED + 1)  # which accepted designs get the brute-force check
    base = run_set("model-made baseline", made_designs, [True] * len(made_designs), lib, index, sample)
    base_time = _median(base.times)
    cases = [
        Case(
            "baseline: model-made designs",
            f"{base.designs} designs",
            100.0 * base.first_shot / max(base.accepted, 1),
            "% first shot",
            f"line's gamut accepts {base.accepted}/{base.designs}, {MAX_COLORANTS}-colorant gamut "
            f"{base.recipe_accepted}; first shot among the latter {base.recipe_first_shot}/"
            f"{base.recipe_accepted}; median {_median(base.sizes):g} colorants; median {base_time:.2f} s "
            f"wall, {_median(base.cpu):.2f} s CPU; load average median {_median(base.loads):.1f}",
        )
    ]
    results: list[SetResult] = []
    for name, paints in sets.items():
        designs = [
            (p.lab_at(np.array(A3)), float(p.gloss_gu if p.gloss_gu is not None else 90.0)) for p in paints
        ]
        physical = [check_paintable(p).paintable for p in paints]
        results.append(run_set(name, designs, physical, lib, index, sample))
        cases += _cases(results[-1], base_time)
        if quick:
            print(cases[-1].line(), cases[-1].note, flush=True)
        else:
            write_section(
                "formulate-independent", "Formulation on independent designs", cases, _extra(results)
            )
    for v in (v for r in results for v in r.brute if v.false_accept or v.false_refusal):
        kind = "false accept" if v.false_accept else "false refusal"
        print(f"{kind}: {v.set_name} #{v.design + 1}: screen {v.screen_de:.2f}, brute force {v.brute_de:.2f}")


def _extra(results: list[SetResult]) -> str:
    verdicts = [v for r in results for v in r.brute]
    fa = [v for v in verdicts if v.false_accept]
    fr = [v for v in verdicts if v.false_refusal]
    listed = "; ".join(
        f"{'false accept' if v.false_accept else 'false refusal'} {v.set_name} #{v.design + 1} "
        f"(screen {v.screen_de:.2f}, brute force {v.brute_de:.2f})"
        for v in fa + fr
    )
    return (
        "Designs the colorant model did not make (bench/formulate_independent.py, seed 2025); SYNTHETIC\n"
        "colorants and demo library. First shot: mean ΔE00 ≤ 1.0 at 15/45/110° after rounding every amount to\n"
        f"0.1 g per 1000 g, at most {MAX_COLORANTS} colorants of the design's toner line, among the designs the\n"
        "gamut check accepts: the physical bound (station.analysis.gamut.check_paintable), the line's gamut\n"
        "(every colorant of the line free) and the N-colorant gamut (station.formulate.gamut.recipe_gamut:\n"
        f"a recipe of at most N = {MAX_COLORANTS} colorants, the selection's subset screen with a continuous\n"
        "refit of its best subsets, amounts unrounded; it does not run the formulation). The figure before\n"
        "the colorant limit (first shot among the line's gamut's accepts) is in each note. Brute force: every\n"
        f"{MAX_COLORANTS}-subset of the line screened, the 25 best refitted and refined, on every miss, every\n"
        "N-colorant refusal and a seeded one-in-four sample of the accepts; over all sets "
        f"{len(verdicts)} designs, {len(fa)} false accepts, {len(fr)} false refusals"
        + (f" ({listed})" if listed else "")
        + ".\nTimes: process CPU and wall medians per design; the machine (2 CPUs) was shared and loaded\n"
        "(load averages in the notes), so the wall figures are several times a quiet machine's.\n"
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    args = bench_cli(__doc__, "formulate_independent", {"--quick": "every fourth design, nothing written"})
    run(quick=args.quick)
