"""Every thesis experiment run on our code, the thesis's number beside ours (``station reproduce``).

One module per chapter (:mod:`~station.reproduce.ch2` … :mod:`~station.reproduce.ch5`, plus
:mod:`~station.reproduce.gloss`), each experiment a function ``run(out_dir) -> ExperimentResult``
listed in :data:`~station.reproduce.registry.EXPERIMENTS`. A :class:`~station.reproduce.core.Quantity`
computes its own verdict from the stated tolerance and refuses to differ without a documented reason.
:mod:`~station.reproduce.report` writes the text table, the JSON records and docs/thesis.md.

This package sits above the peers it exercises (analysis, design, formulate, render, model) and below
the CLI.
"""

from station.reproduce.core import Experiment, ExperimentResult, Figure, Quantity
from station.reproduce.errors import ReproduceError, ReproduceInputError

__all__ = ["Experiment", "ExperimentResult", "Figure", "Quantity", "ReproduceError", "ReproduceInputError"]
