"""Choosing the shared Phong exponents: minimise max + mean fit error over the design database (eq 2.3.4).

    f(E) = max_i Error(E, B_i) + (1/n) Σ_i Error(E, B_i)

Error(E, B_i) is :func:`station.render.lobe_fit.fit_error_de`: the RMS CIEDE2000 over the sample
geometries between design i and its non-negative fit with exponents E. As in thesis §2.3.2, lobes are
added one at a time from 1 to 11 and the optimum for m lobes starts the search for m + 1: the new
exponent is tried at every point of a log-spaced grid, and the best few starts are polished by
Nelder–Mead over all log-exponents (the thesis used Levenberg–Marquardt; f has a max in it, so a
derivative-free search is the safer choice).

Independent of the evaluation cap: Nelder–Mead is run to convergence (simplex within XATOL in
log-exponent and FATOL in f), and restarted from its result with a fresh simplex until a restart
improves f by no more than FATOL (a collapsed simplex is the usual way Nelder–Mead stalls short of a
minimum). ``max_evals`` is only a safety limit per start; a start that reaches it is reported
(``BasisRow.converged`` False), because where a search is cut off, not the objective, would then decide
the answer. The score of a row is f evaluated at the row's own (rounded) exponents, so a row's
numbers are a function of its exponents only. (A capped search, as before, returned the point where the
budget ran out: from 5 lobes on, a different cap gave a different basis and score, and the greedy warm
start carried that into every larger count.)

Reproducible: no random numbers, and the search runs with BLAS/OpenMP pools held to one thread, so the
floating-point sums (and Nelder–Mead's path, which amplifies their last bits) are the same run to run and
machine to machine.

``python -m station.render.basis_selection`` writes the regenerated table to a NEW file
(``lobe_basis.regenerated.json`` in the current directory, or ``--out PATH``); only ``--install``
replaces the shipped station/render/data/lobe_basis.json. ``station reproduce --figure 2.4`` runs the
same search and compares it with the shipped table.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from station.errors import InputError
from station.render import lobe_fit as lf
from station.render.lobes import EXPONENT_RANGE, MAX_LOBES, LobeBasis

#: Search range of a basis exponent (log-spaced grid for each new lobe).
SEARCH_RANGE = (1.0, 2.0e4)
#: Candidate positions tried for each new lobe.
CANDIDATES = 16
#: Convergence of the polish: simplex size in log-exponent, and f (ΔE00); a restart must beat FATOL.
XATOL, FATOL = 1e-3, 1e-4
#: Default safety limit of evaluations per start (not reached by a converging search on the database).
MAX_EVALS = 4000
#: The shipped table (replaced only by ``--install``).
SHIPPED_TABLE = Path(__file__).parent / "data" / "lobe_basis.json"
#: Default output of the command: a new file in the current directory.
DEFAULT_OUT = Path("lobe_basis.regenerated.json")


@dataclass(frozen=True)
class BasisRow:
    """The optimum for one lobe count: exponents and the errors of eq 2.3.4 (CIEDE2000, RMS per design)."""

    lobes: int
    exponents: tuple[float, ...]
    max_error: float
    mean_error: float
    evaluations: int
    seconds: float
    converged: bool = True

    @property
    def objective(self) -> float:
        """f(E) = max + mean (eq 2.3.4)."""
        return self.max_error + self.mean_error


def make_objective(
    brdfs: Sequence[lf.DesignedBRDF], method: str = "nnls", fall_off: bool = False
) -> Callable[[NDArray[np.float64]], tuple[float, float]]:
    """Return E ↦ (max, mean) of Error(E, B_i) over *brdfs* (exponents as an array, any order).

    *fall_off*: fit the aspecular fall-off weight K_A as well (``lobe_fit``); False (default): the thesis's
    model of eq 2.3.4, with which the shipped basis table was selected. The gloss fit is the thesis's
    point-sample fit (``fit_targets(energy=False)``), the one the shipped table was selected with; under
    the energy-conserving fit the product draws with, the one-lobe optimum moves from E = 990 to 756, and
    the table has not been re-selected with it.
    """
    targets = lf.targets_from_brdfs(brdfs)
    reference = lf.designed_reflectance(brdfs)
    from station.model.colorimetry import linear_srgb_to_lab

    ref_lab = linear_srgb_to_lab(reference)

    def errors(exponents: NDArray[np.float64]) -> tuple[float, float]:
        basis = LobeBasis(tuple(np.clip(exponents, *EXPONENT_RANGE)))
        rep = lf.fit_targets(targets, basis, method, fall_off=fall_off, energy=False)
        err = lf.fit_error_de_lab(ref_lab, rep)
        lf.fit_problem.cache_clear()
        return float(err.max()), float(err.mean())

    return errors


def polish(
    f: Callable[[NDArray[np.float64]], float], x0: NDArray[np.float64], max_evals: int
) -> tuple[NDArray[np.float64], float, bool]:
    """(x, f(x), converged): Nelder–Mead from *x0*, restarted until a restart gains ≤ FATOL (module doc).

    *converged* is False when the *max_evals* budget ran out first."""
    from scipy.optimize import minimize

    x = np.asarray(x0, dtype=np.float64)
    fx = float(f(x))
    used = 1
    while used < max_evals:
        res = minimize(
            f,
            x,
            method="Nelder-Mead",
            options={"maxfev": max_evals - used, "xatol": XATOL, "fatol": FATOL, "adaptive": True},
        )
        used += int(res.nfev)
        if not res.success:  # the budget ran out mid-search
            if res.fun < fx:
                x, fx = np.asarray(res.x), float(res.fun)
            return x, fx, False
        if res.fun >= fx - FATOL:
            if res.fun < fx:
                x, fx = np.asarray(res.x), float(res.fun)
            return x, fx, True
        x, fx = np.asarray(res.x), float(res.fun)
    return x, fx, False


def select_bases(
    brdfs: Sequence[lf.DesignedBRDF],
    max_lobes: int = MAX_LOBES,
    max_evals: int = MAX_EVALS,
    log: Callable[[str], None] | None = None,
) -> list[BasisRow]:
    """Greedy forward selection of 1..max_lobes exponents minimising eq 2.3.4 (module docstring).

    Runs with the BLAS/OpenMP thread pools limited to one thread (reproducible sums).
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        return _select_bases(brdfs, max_lobes, max_evals, log)


def _select_bases(
    brdfs: Sequence[lf.DesignedBRDF],
    max_lobes: int,
    max_evals: int,
    log: Callable[[str], None] | None,
) -> list[BasisRow]:
    errors = make_objective(brdfs)
    lo, hi = np.log(SEARCH_RANGE[0]), np.log(SEARCH_RANGE[1])
    grid = np.linspace(lo, hi, CANDIDATES)
    rows: list[BasisRow] = []
    current = np.zeros(0)
    for m in range(1, max_lobes + 1):
        t0 = time.perf_counter()
        evals = 0

        def f(log_e: NDArray[np.float64]) -> float:
            nonlocal evals
            evals += 1
            penalty = np.sum(np.maximum(log_e - hi, 0) + np.maximum(lo - log_e, 0)) * 100.0
            mx, mean = errors(np.exp(np.clip(log_e, lo, hi)))
            return mx + mean + penalty

        starts = sorted(
            ((f(np.sort(np.append(current, g))), tuple(np.sort(np.append(current, g)))) for g in grid),
            key=lambda t: t[0],
        )[:2]
        best_x, best_f = np.asarray(starts[0][1]), starts[0][0]
        converged = True
        for _, x0 in starts:
            x, fx, ok = polish(f, np.asarray(x0), max_evals)
            converged = converged and ok
            if fx < best_f:
                best_x, best_f = x, fx
        exponents = tuple(float(x) for x in np.round(np.exp(np.sort(np.clip(best_x, lo, hi))), 4))
        current = np.log(np.asarray(exponents))
        mx, mean = errors(np.asarray(exponents))  # the row's score: f at its own exponents
        row = BasisRow(m, exponents, mx, mean, evals, time.perf_counter() - t0, converged)
        rows.append(row)
        if log is not None:
            log(
                f"{m:2d} lobes  max {mx:7.3f}  mean {mean:7.3f}  f {mx + mean:7.3f}  "
                f"E = {', '.join(f'{e:.4g}' for e in row.exponents)}  ({evals} evals, {row.seconds:.1f} s"
                + ("" if converged else f", CUT OFF at {max_evals} evaluations per start: not converged")
                + ")"
            )
    return rows


def table_json(rows: Sequence[BasisRow], default_lobes: int, note: str) -> dict[str, object]:
    """The shipped JSON document (schema ``cacad.lobe-basis/1``)."""
    return {
        "schema": "cacad.lobe-basis/1",
        "default_lobes": default_lobes,
        "objective": "eq 2.3.4: max + mean over the design database of RMS CIEDE2000 at the sample geometries",
        "note": note,
        "bases": [
            {
                "lobes": r.lobes,
                "exponents": list(r.exponents),
                "max_error_de": round(r.max_error, 4),
                "mean_error_de": round(r.mean_error, 4),
                "objective": round(r.objective, 4),
            }
            for r in rows
        ],
    }


def output_path(out: Path | None, install: bool) -> Path:
    """Where the command writes: *out*, the shipped table with *install*, else :data:`DEFAULT_OUT`."""
    if install and out is not None:
        raise InputError("--out", "either --out PATH or --install, not both", str(out))
    if install:
        return SHIPPED_TABLE
    return DEFAULT_OUT if out is None else out


def main(argv: Sequence[str] | None = None) -> int:
    """Regenerate the basis table (slow: minutes) into a new file, or the shipped one with ``--install``."""
    import sys

    from station.render.design_db import design_database

    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--max-lobes", type=int, default=MAX_LOBES)
    ap.add_argument("--max-evals", type=int, default=MAX_EVALS, help="safety limit of evaluations per start")
    ap.add_argument("--default-lobes", type=int, default=6)
    ap.add_argument("--out", type=Path, default=None, help=f"output file (default {DEFAULT_OUT})")
    ap.add_argument(
        "--install", action="store_true", help="replace the shipped table station/render/data/lobe_basis.json"
    )
    args = ap.parse_args(argv)
    try:
        out = output_path(args.out, args.install)
        if not 1 <= args.max_lobes <= MAX_LOBES:
            raise InputError("--max-lobes", f"1 to {MAX_LOBES}", args.max_lobes)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    brdfs = [lf.designed_brdf(d) for d in design_database()]
    rows = select_bases(brdfs, args.max_lobes, args.max_evals, log=lambda s: print(s, file=sys.stderr))
    doc = table_json(
        rows,
        args.default_lobes,
        f"{len(brdfs)} designs of station.render.design_db; "
        "regenerate with python -m station.render.basis_selection [--install]",
    )
    out.write_text(json.dumps(doc, indent=1) + "\n")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
