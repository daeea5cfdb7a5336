"""Palette files (cacad.palette/1) round-trip and refuse bad input naming the field; the mood board's
automatic face/flop swap (thesis §3.5.2)."""

from __future__ import annotations

import json

import pytest

from station.design.errors import DesignInputError
from station.design.moodboard import auto_swap_design, face_darker
from station.design.palette import MAX_PALETTE_BYTES, load_palette, save_palette
from station.model import FaceFlopTravelGloss

RED = FaceFlopTravelGloss((45.0, 50.0, 30.0), (20.0, 35.0, 15.0), 62.0, 88.0, name="red")
SOLID = FaceFlopTravelGloss((70.0, 0.0, 0.0), (70.0, 0.0, 0.0), None, 12.0)


def test_palette_round_trip_keeps_names_order_and_every_field(tmp_path):
    p = save_palette([("kept red", RED), ("grey", SOLID)], tmp_path / "p.json")
    data = json.loads(p.read_text())
    assert data["schema"] == "cacad.palette/1"
    assert [e["name"] for e in data["entries"]] == ["kept red", "grey"]
    assert data["entries"][0]["design"]["face"] == [45.0, 50.0, 30.0]
    assert data["entries"][1]["design"]["travel_deg"] is None
    back = load_palette(p)
    assert [n for n, _ in back] == ["kept red", "grey"]
    assert back[0][1] == RED and back[1][1] == SOLID


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("not json", "palette"),
        ('{"schema": "cacad.design/1"}', "schema"),
        ('{"schema": "cacad.palette/1", "entries": {}}', "entries"),
        ('{"schema": "cacad.palette/1", "entries": [{"design": {}}]}', "entries[0].name"),
        (
            '{"schema": "cacad.palette/1", "entries": [{"name": "x", "design": '
            '{"face": [50, 0, 0], "flop": [500, 0, 0], "travel_deg": 60}}]}',
            "entries[0].design",
        ),
    ],
)
def test_bad_palette_files_name_the_field(tmp_path, text, field):
    p = tmp_path / "bad.json"
    p.write_text(text)
    with pytest.raises(DesignInputError) as exc:
        load_palette(p)
    assert exc.value.field == field


def test_missing_and_oversized_palette_files_are_refused(tmp_path):
    with pytest.raises(DesignInputError, match="palette"):
        load_palette(tmp_path / "nope.json")
    big = tmp_path / "big.json"
    big.write_bytes(b" " * (MAX_PALETTE_BYTES + 1))
    with pytest.raises(DesignInputError, match=str(MAX_PALETTE_BYTES)):
        load_palette(big)


def test_auto_swap_only_when_the_face_is_darker():
    dark_face = RED.replace(face=RED.flop, flop=RED.face)  # face L* 20 < flop L* 45
    assert face_darker(dark_face.face, dark_face.flop) and not face_darker(RED.face, RED.flop)
    swapped, did = auto_swap_design(dark_face)
    assert did and swapped.face == RED.face and swapped.flop == RED.flop
    assert swapped.travel_deg == RED.travel_deg and swapped.gloss_gu == RED.gloss_gu
    same, did = auto_swap_design(RED)
    assert not did and same is RED
    # equal L* is not darker: nothing to swap
    assert auto_swap_design(SOLID) == (SOLID, False)
