"""``station design …`` commands end to end (JSON output, exit statuses)."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest
from PIL import Image

from station.cli import main
from station.design import artwork
from station.design.images import load_image
from station.model.colorimetry import lab_to_linear_srgb, srgb_encode


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, Any, str]:
    code = main(list(argv))
    out = capsys.readouterr()
    return code, (json.loads(out.out) if out.out.strip() and code == 0 else None), out.err


def test_variations_json(capsys) -> None:
    code, data, _ = _run(
        capsys,
        "design",
        "variations",
        "--face",
        "60,30,10",
        "--flop",
        "25,20,15",
        "--travel",
        "70",
        "--degree",
        "4",
        "--category",
        "face",
        "--json",
    )
    assert code == 0 and data["category"] == "face"
    assert [v["label"] for v in data["variations"]][:2] == ["lighter", "darker"]
    assert data["variations"][0]["design"]["face"][0] == pytest.approx(64.0)


def test_variations_bad_degree_exits_2(capsys) -> None:
    code, _, err = _run(capsys, "design", "variations", "--face", "60,30,10", "--degree", "0", "--json")
    assert code == 2 and "degree" in err


def test_eyedrop_json(tmp_path, capsys) -> None:
    img = np.zeros((20, 40, 3), dtype=np.uint8)
    img[:, :20] = np.round(srgb_encode(lab_to_linear_srgb([60.0, 20.0, 10.0])) * 255)
    img[:, 20:] = np.round(srgb_encode(lab_to_linear_srgb([30.0, 10.0, 15.0])) * 255)
    Image.fromarray(img).save(tmp_path / "board.png")
    code, data, _ = _run(
        capsys,
        "design",
        "eyedrop",
        str(tmp_path / "board.png"),
        "--face",
        "30,10",
        "--flop",
        "5,10",
        "--gloss",
        "20,10",
        "--travel",
        "65",
        "--radius",
        "2",
        "--json",
    )
    assert code == 0 and data["swapped"] is True
    assert data["design"]["face"] == pytest.approx([60.0, 20.0, 10.0], abs=0.6)
    assert data["design"]["travel_deg"] == 65.0 and "gloss" in data
    code, _, err = _run(
        capsys, "design", "eyedrop", str(tmp_path / "board.png"), "--face", "99,10", "--flop", "5,10"
    )
    assert code == 2 and "xy" in err


def test_render_then_sketch_fit_json(tmp_path, capsys) -> None:
    code, data, _ = _run(
        capsys,
        "design",
        "render",
        "--face",
        "60,30,10",
        "--flop",
        "25,20,15",
        "--travel",
        "70",
        "--size",
        "64",
        "--out",
        str(tmp_path / "goal.png"),
        "--json",
    )
    assert code == 0
    goal = load_image(tmp_path / "goal.png").pixels
    code, _, _ = _run(
        capsys, "design", "render", "--size", "64", "--out", str(tmp_path / "init.png"), "--json"
    )
    art = artwork.rotate_hue(goal, 90.0, goal.max(axis=-1) > 0)
    Image.fromarray(np.round(art * 255).astype(np.uint8)).save(tmp_path / "art.png")
    code, data, _ = _run(
        capsys,
        "design",
        "sketch-fit",
        "--scene",
        "sphere-point",
        "--art",
        str(tmp_path / "art.png"),
        "--json",
    )
    assert code == 0
    assert set(data) >= {"design", "rms_de", "failed", "seconds"}
    assert data["failed"] is False and data["rms_de"] < 2.0
    assert data["design"]["schema"] == "cacad.design/1"


def test_palette_writes_pngs(tmp_path, capsys) -> None:
    code, data, _ = _run(
        capsys,
        "design",
        "palette",
        "--face",
        "60,30,10",
        "--flop",
        "25,20,15",
        "--travel",
        "70",
        "--out",
        str(tmp_path / "red"),
        "--json",
    )
    assert code == 0
    with Image.open(data["swatch"]) as swatch, Image.open(data["booklet"]) as booklet:
        assert swatch.size == (160, 32)
        assert booklet.size == (96, 96)


def test_sketch_fit_rejects_wrong_size_art(tmp_path, capsys) -> None:
    Image.new("RGB", (30, 20)).save(tmp_path / "art.png")
    code, _, err = _run(capsys, "design", "sketch-fit", "--art", str(tmp_path / "art.png"))
    assert code == 2 and "art" in err
