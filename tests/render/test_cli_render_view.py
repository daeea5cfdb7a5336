"""``station render --view``, ``--mesh car`` and the ``--flake-*`` parameters, and their input errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from PIL import Image

from station.cli import main
from station.model import FaceFlopTravelGloss
from station.model.design_io import save_design
from station.render import procedural
from station.render.camera import orbit_camera
from station.render.hdr_io import write_hdr
from station.render.shapes import Scene


@pytest.fixture()
def files(tmp_path):
    design = tmp_path / "silver.json"
    save_design(FaceFlopTravelGloss((80.0, 0.0, -2.0), (35.0, 0.0, -3.0), 70.0, 88.0), design)
    env = tmp_path / "sky.hdr"
    write_hdr(env, procedural.sunny_sky(64).equirect)
    return design, env


def _run(files, tmp_path, capsys, *extra: str) -> tuple[int, dict | str]:
    design, env = files
    rc = main(
        [
            "render",
            "--design",
            str(design),
            "--env",
            str(env),
            "--size",
            "24",
            "--out",
            str(tmp_path / "o.png"),
            "--cache-dir",
            str(tmp_path / "c"),
            "--json",
            *extra,
        ]
    )
    captured = capsys.readouterr()
    return rc, (json.loads(captured.out) if rc == 0 else captured.err)


def test_orbit_camera_closed_form() -> None:
    cam = orbit_camera((1.0, 0.0, 0.0), 90.0, 30.0, 2.0, 25.0)
    # yaw 90° from +x, pitch 30°: eye = target + 2 (cos 30° · 1, sin 30°, cos 30° · 0)
    assert cam.eye == pytest.approx((1.0 + 2.0 * math.cos(math.radians(30.0)), 1.0, 0.0), abs=1e-12)
    assert cam.target == (1.0, 0.0, 0.0) and cam.fov_deg == 25.0


def test_view_frames_a_close_up_and_flake_parameters(files, tmp_path, capsys) -> None:
    rc, result = _run(
        files,
        tmp_path,
        capsys,
        "--engine",
        "numpy",
        "--shape",
        "speedshape",
        "--view",
        "30,15,0.8",
        "--flake-size",
        "40",
        "--flake-density",
        "200",
        "--flake-spread",
        "6",
    )
    assert rc == 0, result
    assert isinstance(result, dict)
    target = Scene("speedshape").view_camera.target
    eye = np.asarray(result["view"]["eye"])
    assert np.linalg.norm(eye - np.asarray(target)) == pytest.approx(0.8, abs=1e-3)
    assert eye[1] - target[1] == pytest.approx(0.8 * math.sin(math.radians(15.0)), abs=1e-3)
    layer = result["flake_layer"]
    assert (layer["size_um"], layer["density_per_mm2"], layer["spread_deg"]) == (40.0, 200.0, 6.0)
    assert "per pixel" in result["flakes"]


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        (["--view", "30"], "view"),
        (["--view", "a,b"], "view"),
        (["--view", "0,95"], "view.pitch"),
        (["--view", "0,10,-1"], "view.distance"),
        (["--flake-size", "0"], "flakes.size_um"),
        (["--flake-spread", "90"], "flakes.spread_deg"),
        (["--flake-density", "1e9"], "flakes.density_per_mm2"),
    ],
)
def test_bad_values_exit_2_naming_the_field(files, tmp_path, capsys, extra, field) -> None:
    rc, err = _run(files, tmp_path, capsys, "--engine", "numpy", *extra)
    assert rc == 2
    assert isinstance(err, str) and field in err and len(err.strip().splitlines()) == 1


@pytest.mark.gl
def test_mesh_car_is_the_procedural_car(files, tmp_path, capsys, gl_ctx) -> None:
    rc, result = _run(files, tmp_path, capsys, "--engine", "gl", "--stage", "--mesh", "car", "--size", "48")
    assert rc == 0, result
    assert isinstance(result, dict) and result["shape"] == "car"
    img = np.asarray(Image.open(tmp_path / "o.png"))
    assert img.shape == (48, 48, 3)
