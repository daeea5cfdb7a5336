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

Each design goes through the paintability check (:func:`station.analysis.gamut.check_paintable`), then
:func:`station.formulate.formulation.formulate_from_library` with the demo library and the default
limits (toner line from the type, at most 5 colorants, amounts rounded to 0.1 g per 1000 g). Per set:
the share the gamut check accepts; of those, the share within mean ΔE00 ≤ 1.0 at 15/45/110° first shot
with a weighable recipe (every amount a multiple of the resolution, bar ≥ 95 %); the median number of
colorants; the median formulation time (bar ≤ 1 s). Baseline, same run: 20 designs the colorant model
did make (predictions of generator recipes), through the same steps.

Run: ``nice python -m bench.formulate_independent`` (ten minutes or more on a loaded machine).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bench._report import Case, write_section
from station.analysis.gamut import check_paintable
from station.analysis.scenarios import BUMPER_PAINT, SILVER_PAINT, SOLID_PAINT
from station.formulate.colorants import predict_lab
from station.formulate.demo import demo_library, generate_recipes
from station.formulate.formulation import formulate_from_library
from station.formulate.library import Library
from station.formulate.snap import SnapIndex
from station.model import AspecularMeasurements, FaceFlopTravelGloss
from station.model.examples import BRIGHT_SILVER, HUE_SHIFT_PEARL, RED_METALLIC, SILVER, SOLID_WHITE
from station.model.fit import fit_fftg

A3 = (15.0, 45.0, 110.0)
SEED = 2025
RESOLUTION_G = 0.1
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
    accepted: int
    first_shot: int
    sizes: list[int]
    times: list[float]


def _weighable(grams: dict[str, float]) -> bool:
    return all(
        g >= RESOLUTION_G - 1e-9 and abs(g / RESOLUTION_G - round(g / RESOLUTION_G)) < 1e-6
        for g in grams.values()
    )


def run_set(
    name: str,
    designs: list[tuple[np.ndarray, float]],
    accept: Callable[[int], bool],
    lib: Library,
    index: SnapIndex,
) -> SetResult:
    res = SetResult(name, len(designs), 0, 0, [], [])
    for k, (lab, gloss) in enumerate(designs):
        if not accept(k):
            continue
        res.accepted += 1
        t0 = time.perf_counter()
        r, _ = formulate_from_library(lab, lib, index, gloss_gu=gloss)
        res.times.append(time.perf_counter() - t0)
        res.sizes.append(r.recipes[0].colorants)
        if r.formulable and _weighable(r.recipes[0].grams):
            res.first_shot += 1
        print(f"  {name} {k + 1}/{len(designs)}: {r.mean_de:.2f} {res.times[-1]:.2f} s", flush=True)
    print(f"{name}: {res.first_shot}/{res.accepted} of {res.designs}", flush=True)
    return res


def _cases(r: SetResult, base_time: float) -> list[Case]:
    share = 100.0 * r.first_shot / max(r.accepted, 1)
    t = float(np.median(r.times)) if r.times else float("nan")
    note = (
        f"gamut check accepts {r.accepted}/{r.designs}; first shot {r.first_shot}/{r.accepted} "
        f"({'meets' if share >= 95 else 'misses'} the 95 % bar); median {np.median(r.sizes) if r.sizes else 0:g} "
        f"colorants; median {t:.2f} s ({'meets' if t <= 1.0 else 'misses'} the 1 s bar), "
        f"{t / base_time:.2f}× the model-made baseline"
    )
    return [Case(f"independent: {r.name}", f"{r.designs} designs", share, "% first shot", note)]


def run() -> None:
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
    base = run_set("model-made baseline", model_made(20), lambda _k: True, lib, index)
    base_time = float(np.median(base.times))
    cases = [
        Case(
            "baseline: model-made designs",
            "20 designs",
            100.0 * base.first_shot / base.designs,
            "% first shot",
            f"median {np.median(base.sizes):g} colorants; median {base_time:.2f} s",
        )
    ]
    for name, paints in sets.items():
        designs = [
            (p.lab_at(np.array(A3)), float(p.gloss_gu if p.gloss_gu is not None else 90.0)) for p in paints
        ]
        ok = [check_paintable(p).paintable for p in paints]
        cases += _cases(run_set(name, designs, ok.__getitem__, lib, index), base_time)
        write_section("formulate-independent", "Formulation on independent designs", cases, _EXTRA)


_EXTRA = (
    "Designs the colorant model did not make (bench/formulate_independent.py, seed 2025); SYNTHETIC colorants\n"
    "and demo library. First shot: mean ΔE00 ≤ 1.0 at 15/45/110° after rounding every amount to 0.1 g per\n"
    "1000 g, at most 5 colorants of the design's toner line. Gamut check: station.analysis.gamut.check_paintable.\n"
)


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "formulate_independent")
    run()
