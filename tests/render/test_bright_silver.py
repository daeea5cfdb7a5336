"""The bright silver (L*15 = 125) through the renderer: lobe fit and NumPy render, finite and brighter
than the same silver with an L*90 face.

Independent expectation: with the same flop, travel and gloss, X(θ) = flop + (face − flop)·s(θ)² is
at least as light at every angle for the brighter face and strictly lighter below the travel angle,
so the designed BRDF, and the rendered panel, carry more light everywhere the face shows.
"""

from __future__ import annotations

import json

import numpy as np

from station.cli import main
from station.model import FaceFlopTravelGloss
from station.model.design_io import save_design
from station.render import lobe_fit, procedural
from station.render.hdr_io import write_hdr


def _l90(design: FaceFlopTravelGloss) -> FaceFlopTravelGloss:
    return design.replace(face=(90.0, *design.face[1:]), name="L*90 silver")


def test_lobe_weights_are_finite_and_brighter(bright_silver: FaceFlopTravelGloss) -> None:
    bright, dim = lobe_fit.fit_design(bright_silver), lobe_fit.fit_design(_l90(bright_silver))
    for w in (bright, dim):
        for part in (w.k_d, w.k_dd, w.k_g):
            assert np.all(np.isfinite(part)) and np.all(np.asarray(part) >= 0.0)
    assert np.sum(bright.k_dd) + np.sum(bright.k_d) > np.sum(dim.k_dd) + np.sum(dim.k_d)


def test_render_is_finite_and_brighter_than_an_l90_silver(bright_silver, tmp_path, capsys) -> None:
    a, b = tmp_path / "bright.json", tmp_path / "l90.json"
    save_design(bright_silver, a)
    save_design(_l90(bright_silver), b)
    env = tmp_path / "sky.hdr"
    write_hdr(env, procedural.sunny_sky(64).equirect)
    lin = tmp_path / "o.npy"
    args = ["render", "--design", str(a), "--design2", str(b), "--env", str(env), "--shape", "panels"]
    args += ["--size", "24", "--engine", "numpy", "--out", str(tmp_path / "o.png"), "--linear-out", str(lin)]
    rc = main([*args, "--cache-dir", str(tmp_path / "cache"), "--json"])
    assert rc == 0
    assert json.loads(capsys.readouterr().out)["engine"] == "numpy"
    linear = np.load(lin)
    assert linear.shape == (24, 24, 3) and np.isfinite(linear).all()
    left, right = linear[8:16, 4:10].mean((0, 1)), linear[8:16, 14:20].mean((0, 1))  # bright | L*90
    assert np.all(left > right)
