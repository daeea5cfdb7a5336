"""The one size-capped JSON reader behind design and palette files (station.model.design_io)."""

from __future__ import annotations

import json

import pytest

from station.design.errors import DesignInputError
from station.design.palette import MAX_PALETTE_BYTES, load_palette, save_palette
from station.errors import InputError
from station.model.design_io import (
    MAX_DESIGN_BYTES,
    load_design,
    load_design_flakes,
    read_json_file,
    save_design,
)
from station.model.errors import ModelInputError
from station.model.representations import FaceFlopTravelGloss


def _design() -> FaceFlopTravelGloss:
    return FaceFlopTravelGloss(
        face=(60.0, 20.0, 10.0), flop=(30.0, 25.0, 12.0), travel_deg=60.0, gloss_gu=85.0
    )


def test_a_design_round_trips_and_its_flakes_come_from_the_same_read(tmp_path):
    path = save_design(_design(), tmp_path / "d.json")
    assert load_design(path) == _design()
    design, flakes = load_design_flakes(path)
    assert design == _design()
    assert flakes is not None  # an effect paint without a "flakes" key takes the metallic default


@pytest.mark.parametrize(
    ("write", "accepted"),
    [
        (None, "a readable design file"),
        (b"{not json", "a JSON design file"),
        (b"\xff\xfe", "a JSON design file"),
    ],
)
def test_a_bad_design_file_names_the_field(tmp_path, write, accepted):
    path = tmp_path / "d.json"
    if write is not None:
        path.write_bytes(write)
    with pytest.raises(ModelInputError) as err:
        load_design(path)
    assert err.value.field == "design"
    assert accepted in str(err.value)


def test_a_file_one_byte_over_the_cap_is_refused_before_it_is_parsed(tmp_path):
    path = tmp_path / "big.json"
    path.write_bytes(b" " * (MAX_DESIGN_BYTES + 1))
    with pytest.raises(ModelInputError, match=f"at most {MAX_DESIGN_BYTES} bytes"):
        load_design_flakes(path)
    path.write_bytes(b" " * (MAX_DESIGN_BYTES - 2) + b"{}")
    assert read_json_file(path, "design", "design file", MAX_DESIGN_BYTES) == {}


def test_palette_files_use_the_same_reader_with_their_own_error_and_cap(tmp_path):
    path = save_palette([("a", _design())], tmp_path / "p.json")
    assert load_palette(path)[0][1] == _design()
    assert json.loads(path.read_text())["schema"] == "cacad.palette/1"
    path.write_bytes(b" " * (MAX_PALETTE_BYTES + 1))
    with pytest.raises(DesignInputError) as err:
        load_palette(path)
    assert isinstance(err.value, InputError)
    assert err.value.field == "palette"
