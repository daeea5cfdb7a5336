"""Calibrating the default lobe basis on the demo library's own distribution (a training split).

Run: ``.venv/bin/python -m bench.library_basis [--per-class N] [--rounds R] [--write]``. The basis table
of :mod:`station.render.basis_selection` is chosen on the 40 designs of the thesis's design database
(eq 2.3.4), most of whose effect designs travel 95–165°; 89 % of the demo library's effect paints travel
less than 90°, and on them the table's 6-lobe basis leaves the colour between 15° and 70° to two wide
lobes (E 2.2 and 14) and the gloss lobes (E ≥ 238): the fitted colour alone is 2.2–3.0 ΔE00 (p95) off the
designed colour on the sky and the studio HDR.

The calibration: a stratified TRAINING split of the library (``bench.library_accuracy.sample_paints``
with ``split="train"``: --per-class paints of each class, seed TRAIN_SEED, drawn from the paints the
benchmark's held-out sample never holds), shaded exactly as ``bench.library_accuracy`` shades (default
perceptual fit, NumPy renderer, every built-in and shared environment against the truth engine). The
score of a basis is the worst (class, environment) cell's distance to the bar, max(p95 / 2.3, mean / 1.0);
the mean of the cells' p95 is reported beside it. Search: coordinate descent in log-exponent from the table's
6-lobe row — each exponent in turn tried at × STEPS (¼, ½, 2, 4), a move kept when it lowers the score by MIN_GAIN — for
--rounds rounds or until no move helps. The lobe count stays 6 (the renderers' cost).

The shipped default is the table's row together with the lobes the search moved (the row's lobe kept
beside its moved copy): with the moved lobe alone (E 2.24 → 4.49) the design database's own accuracy test
missed its bar on four environments (p95 up to 2.83), with both it meets it. ``--write`` stores that
union and the search's own best (``calibrated``) after every improvement as station/render/data/lobe_basis_library.json, which
:func:`station.render.lobes.default_basis` reads; the table keeps the thesis's design-database bases
(``basis_for_count``). The held-out figures are ``bench.library_accuracy``'s.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from bench.env_accuracy import MEAN_BAR, P95_BAR, SPHERE, environments, ndv_of, reflect_of
from bench.library_accuracy import CLASSES, TRAIN_SEED, sample_paints
from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.render import lobe_fit as lf
from station.render import numpy_renderer as nr
from station.render import truth as tr
from station.render.envcache import PrefilterCache
from station.render.lobes import LIBRARY_BASIS, LobeBasis, basis_for_count
from station.render.prefilter import prefilter_basis

#: Multiplicative steps of the coordinate search, tried in turn on each exponent.
STEPS = (0.25, 0.5, 2.0, 4.0)
#: A move is kept when it lowers the worst cell's score by at least this (1 % of the bar): the score of a
#: 40-paint split moves by a few thousandths between near-equal bases (a first run kept a lobe at 1470
#: beside one at 1437 for 0.002, and the sharpest lobe pushed to the range's end for 0.004).
MIN_GAIN = 0.01
#: Range of a basis exponent: 1 to 5000 (a sharper lobe needs cube faces beyond the renderers' 256).
EXPONENTS = (1.0, 5000.0)


class Calibration:
    """The training split's truth, per environment, and the score of a basis on it (module docstring)."""

    def __init__(self, per_class: int) -> None:
        designs, names, self.failed = sample_paints(per_class, split="train")
        self.count = len(designs)
        self.cls = np.array(names)
        self.targets = lf.targets_from_brdfs([lf.designed_brdf(d) for d in designs])
        brdfs = [lf.designed_brdf(d) for d in designs]
        self.normals, self.views = tr.sphere_pixels(SPHERE)
        self.ndv, self.refl = ndv_of(self.normals, self.views), reflect_of(self.normals, self.views)
        self.envs = environments()
        self.cache = PrefilterCache(tempfile.mkdtemp(prefix="library-basis-"))  # maps reused across moves
        self.refs: list[tuple[float, list[np.ndarray]]] = []
        for env in self.envs:
            scene = tr.TruthScene(env, self.normals, self.views)
            white = float(scene.white()[..., 1].max())
            self.refs.append((white, [linear_srgb_to_lab(scene.truth(b) / white) for b in brdfs]))

    def cells(self, exponents: tuple[float, ...]) -> dict[tuple[str, str], tuple[float, float]]:
        """(environment, class) → (mean, p95) ΔE00 of the training split shaded with *exponents*."""
        basis = LobeBasis(tuple(exponents))
        rep = lf.fit_targets(self.targets, basis)
        out = {}
        for env, (white, refs) in zip(self.envs, self.refs, strict=True):
            pb = prefilter_basis(env, basis.exponents, engine="auto", cache=self.cache)
            de = np.stack(
                [
                    delta_e(
                        ref,
                        linear_srgb_to_lab(
                            nr.shade_pixels(pb, rep.weights(i), self.normals, self.refl, self.ndv) / white
                        ),
                        "cie2000",
                    )
                    for i, ref in enumerate(refs)
                ]
            )
            for c in CLASSES:
                d = de[self.cls == c]
                out[(env.name, c)] = (float(d.mean()), float(np.percentile(d, 95.0)))
        return out

    def score(self, exponents: tuple[float, ...]) -> tuple[float, float]:
        """(worst cell's max(p95 / P95_BAR, mean / MEAN_BAR), mean p95 over the cells)."""
        cells = self.cells(exponents).values()
        worst = max(max(p95 / P95_BAR, mean / MEAN_BAR) for mean, p95 in cells)
        return worst, float(np.mean([p95 for _, p95 in cells]))


def search(
    cal: Calibration,
    start: tuple[float, ...],
    rounds: int,
    log: Callable[[str], None] = print,
    keep: Callable[[tuple[float, ...], tuple[float, float], str], None] | None = None,
) -> tuple[tuple[float, ...], tuple[float, float]]:
    """Coordinate descent in log-exponent from *start* (module docstring): (exponents, score). *keep* is
    called with every improvement (exponents, score, progress), so an interrupted search leaves its best."""
    best = tuple(sorted(start))
    best_s = cal.score(best)
    log(f"start {best}: worst {best_s[0]:.3f}, mean p95 {best_s[1]:.3f}")
    evals = 1
    for r in range(rounds):
        moved = False
        for i in range(len(best)):
            for step in STEPS:
                cand = list(best)
                cand[i] = float(np.clip(round(cand[i] * step, 4), *EXPONENTS))
                cand_t = tuple(sorted(cand))
                if len(set(cand_t)) < len(cand_t):
                    continue
                s = cal.score(cand_t)
                evals += 1
                if s[0] < best_s[0] - MIN_GAIN:
                    best, best_s, moved = cand_t, s, True
                    log(f"round {r + 1}: {best}: worst {s[0]:.3f}, mean p95 {s[1]:.3f} ({evals} evaluations)")
                    if keep is not None:
                        keep(best, best_s, f"round {r + 1} of {rounds}, {evals} evaluations")
        if not moved:
            break
    return best, best_s


def _arguments(argv: list[str] | None) -> argparse.Namespace:
    """The command line, parsed before anything is measured (``--help`` prints the module's doc)."""
    ap = argparse.ArgumentParser(
        prog="python -m bench.library_basis",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="runs the calibration; with --write it rewrites station/render/data/lobe_basis_library.json "
        "after every improvement (docs/benchmarks.md is bench.library_accuracy's to write)",
    )
    ap.add_argument("--per-class", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--write", action="store_true", help="store the result as the shipped default basis")
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = _arguments(argv)
    t0 = time.perf_counter()
    cal = Calibration(args.per_class)
    print(
        f"training split: {cal.count} paints, {cal.failed} without a model fit ({time.perf_counter() - t0:.0f} s)"
    )
    start = basis_for_count(6).exponents

    def keep(best: tuple[float, ...], score: tuple[float, float], progress: str) -> None:
        if not args.write:
            return
        doc = {
            "schema": "cacad.lobe-basis-library/1",
            # the row's lobes and the moved ones: the design database keeps its bar (module docstring)
            "exponents": sorted(set(start) | set(best)),
            "calibrated": list(best),
            "calibration": (
                f"python -m bench.library_basis --per-class {args.per_class} --rounds {args.rounds}: training "
                f"split of the demo library ({cal.count} paints, seed {TRAIN_SEED}, disjoint from "
                f"bench.library_accuracy's held-out sample), {len(cal.envs)} environments, from the table's "
                f"6-lobe row; {progress}; worst cell {score[0]:.3f} of the bar, mean p95 {score[1]:.3f}"
            ),
            "start": list(start),
        }
        Path(LIBRARY_BASIS).write_text(json.dumps(doc, indent=1) + "\n")

    best, (worst, mean_p95) = search(cal, start, args.rounds, log=lambda s: print(s, flush=True), keep=keep)
    print(
        f"chosen {best}: worst cell {worst:.3f} of the bar, mean p95 {mean_p95:.3f} ({time.perf_counter() - t0:.0f} s)"
    )
    if args.write:
        print(f"wrote {LIBRARY_BASIS}")


if __name__ == "__main__":
    main()
