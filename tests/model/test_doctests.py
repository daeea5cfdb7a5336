"""The ``>>>`` examples in the model's docstrings run as tests (colour-science's habit).

Each example's value was checked against an independent calculation written beside it (a closed form,
Sharma et al.'s published CIEDE2000 pairs, the Fresnel equations by hand), so an example that drifts
from the code fails here rather than misleading a reader. Every module of ``station/model`` holding an
example is run; :data:`EXPECTED` lists the ones that must hold examples, with their least count, so an
example deleted by accident fails too.
"""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

MODEL = Path(__file__).resolve().parents[2] / "station" / "model"

#: Modules of the model's public numerics and the least number of examples each must run.
EXPECTED = {
    "station.model.domain": 13,
    "station.model.angles": 3,
    "station.model.representations": 4,
    "station.model.difference": 12,
    "station.model.indices": 4,
    "station.model.gloss": 4,
    "station.model.fresnel": 2,
    "station.model.spectra": 4,
    "station.model.colorimetry": 7,
    "station.model.cie2000": 4,
}


def _modules_with_examples() -> list[str]:
    return sorted(
        f"station.model.{p.stem}" for p in MODEL.glob("*.py") if ">>>" in p.read_text(encoding="utf-8")
    )


def test_the_expected_modules_hold_examples() -> None:
    assert set(EXPECTED) <= set(_modules_with_examples())


@pytest.mark.parametrize("name", _modules_with_examples())
def test_docstring_examples(name: str) -> None:
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    for test in finder.find(module, name):
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, (
        f"{result.failed} of {result.attempted} examples in {name} failed (output above)"
    )
    assert result.attempted >= EXPECTED.get(name, 1)
