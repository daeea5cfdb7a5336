"""Brute force over colorant subsets, for the tests of the subset search and the N-colorant gamut: the
best recipe of exactly a given set of colorants, refitted from several starts."""

from __future__ import annotations

import numpy as np

from station.formulate.colorants import default_database, predict_lab
from station.formulate.de_kernels import cie2000
from station.formulate.lines import toner_line
from station.formulate.solver import Objective, Problem, fit_lab, refine_de00

A3 = (15.0, 45.0, 110.0)
DB = default_database()
#: The solid toner line's colorant indices in DB.
SOLID = np.flatnonzero(toner_line("solid").mask(DB))


def best_fit(design: np.ndarray, free: tuple[int, ...]) -> float:
    """Mean ΔE00 of the best recipe of exactly the colorants *free*, from three starts (brute force)."""
    prob = Problem(design, A3, DB, np.array(free), np.zeros(len(DB.names)))
    obj = Objective(prob)
    for scale in (0.02, 0.1, 0.3):
        _, x = fit_lab(obj, np.full(len(free), scale / len(free)), max_nfev=60)
        refine_de00(obj, x, 1e-8, maxiter=120)
    return float(cie2000(design, predict_lab(prob.full(obj.best[1]), A3, DB)).mean())
