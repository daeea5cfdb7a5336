"""Colour sequences (thesis §5.4.4): principal colours kept, steps evenly spaced by CIEDE2000 as an
independent implementation (colour-science) measures them, bad input refused."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from station.formulate.sequence import colour_sequence
from station.model import FaceFlopTravelGloss
from station.model.errors import ModelInputError

SILVER = FaceFlopTravelGloss((95.0, -1.0, -3.0), (35.0, 0.0, -2.0), 70.0, 90.0, name="silver")
BLUE = FaceFlopTravelGloss((60.0, -5.0, -40.0), (22.0, 2.0, -22.0), 65.0, 85.0, name="blue")
RED = FaceFlopTravelGloss((55.0, 40.0, 25.0), (20.0, 25.0, 12.0), 75.0, 88.0, name="red")
GREY = FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None, 60.0, name="grey")
ANGLES = np.array([15.0, 45.0, 110.0])


def _d(p: FaceFlopTravelGloss, q: FaceFlopTravelGloss) -> float:
    """Mean CIEDE2000 over 15/45/110 by colour-science (not the product's kernel)."""
    return float(np.mean(colour.delta_E(p.lab_at(ANGLES), q.lab_at(ANGLES), method="CIE 2000")))


def test_principal_colours_are_steps_and_spacing_is_even_within_segments() -> None:
    seq = colour_sequence([SILVER, BLUE, RED], 9)
    assert len(seq.designs) == 9 and seq.principal_steps[0] == 0 and seq.principal_steps[-1] == 8
    for step, principal in zip(seq.principal_steps, (SILVER, BLUE, RED), strict=True):
        got = seq.designs[step]
        assert np.allclose(got.lab_at(ANGLES), principal.lab_at(ANGLES), atol=1e-9)
        assert got.gloss_gu == pytest.approx(principal.gloss_gu)
    steps = [_d(p, q) for p, q in zip(seq.designs[:-1], seq.designs[1:], strict=True)]
    assert steps == pytest.approx(list(seq.step_de), rel=1e-6)  # the reported spacing is the real one
    cut = seq.principal_steps[1]
    for part in (steps[:cut], steps[cut:]):
        assert max(part) / min(part) < 1.01  # even within a segment
    assert max(steps) / min(steps) < 1.1  # and as even as whole steps allow across segments


def test_even_by_eye_not_by_parameter() -> None:
    """Lightness steps of equal size in L* are not equal in CIEDE2000 (S_L grows away from L* 50); the
    sequence's steps are."""
    dark = FaceFlopTravelGloss((20.0, 0.0, 0.0), (20.0, 0.0, 0.0), None, 90.0)
    light = FaceFlopTravelGloss((95.0, 0.0, 0.0), (95.0, 0.0, 0.0), None, 90.0)
    seq = colour_sequence([dark, light], 6)
    steps = [_d(p, q) for p, q in zip(seq.designs[:-1], seq.designs[1:], strict=True)]
    assert max(steps) / min(steps) < 1.01
    faces = np.array([d.face[0] for d in seq.designs])
    assert np.ptp(np.diff(faces)) > 1.0  # the L* increments differ: spacing is not parametric


def test_a_solid_next_to_a_metallic_keeps_its_colour() -> None:
    seq = colour_sequence([GREY, SILVER], 4)
    assert np.allclose(seq.designs[0].lab_at(ANGLES), 50.0 * np.array([[1, 0, 0]] * 3), atol=1e-9)
    assert seq.designs[0].travel_deg == SILVER.travel_deg


@pytest.mark.parametrize(
    ("principals", "steps", "field"),
    [([SILVER], 5, "principals"), ([SILVER, BLUE, RED], 2, "steps"), ([SILVER, BLUE], 201, "steps")],
)
def test_bad_input_names_the_field(principals: list[FaceFlopTravelGloss], steps: int, field: str) -> None:
    with pytest.raises(ModelInputError, match=field):
        colour_sequence(principals, steps)


def test_cli_writes_a_palette_the_viewer_opens(tmp_path) -> None:
    import json

    from station.design.palette import load_palette
    from station.model.design_io import save_design
    from tests.user_cli import run_station

    save_design(SILVER, tmp_path / "silver.json")
    save_design(BLUE, tmp_path / "blue.json")
    run = run_station(
        tmp_path, "sequence", "silver.json", "blue.json", "--steps", "5", "--out", "wall.json", "--json"
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    entries = load_palette(tmp_path / "wall.json")
    assert [name for name, _ in entries] == [f"step {i}" for i in range(1, 6)]
    want = colour_sequence([SILVER, BLUE], 5)
    for (_, got), ref in zip(entries, want.designs, strict=True):
        assert np.allclose(got.lab_at(ANGLES), ref.lab_at(ANGLES), atol=1e-9)
    assert out["step_de"] == pytest.approx(list(want.step_de))
    bad = run_station(tmp_path, "sequence", "silver.json", "--steps", "5")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "principals" in bad.stderr
