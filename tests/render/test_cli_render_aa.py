"""``station render --aa N``: anti-aliasing of the GL engine on by default, off with 1, refused counts exit 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.cli import main
from station.model import FaceFlopTravelGloss
from station.model.design_io import save_design
from station.render.gl_targets import DEFAULT_AA


@pytest.fixture()
def design(tmp_path):
    path = tmp_path / "a.json"
    save_design(FaceFlopTravelGloss((60.0, 10.0, -40.0), (30.0, 5.0, -30.0), 60.0, 85.0), path)
    return path


def _args(design, tmp_path, name: str, *extra: str) -> list[str]:
    return [
        "render",
        "--design",
        str(design),
        "--env",
        "booth",
        "--size",
        "24",
        "--out",
        str(tmp_path / f"{name}.png"),
        "--linear-out",
        str(tmp_path / f"{name}.npy"),
        "--cache-dir",
        str(tmp_path / "c"),
        "--json",
        *extra,
    ]


@pytest.mark.gl
def test_render_aa_default_and_off(design, tmp_path, capsys, gl_ctx):
    assert main(_args(design, tmp_path, "on", "--engine", "gl")) == 0
    assert json.loads(capsys.readouterr().out)["aa"] == DEFAULT_AA
    assert main(_args(design, tmp_path, "off", "--engine", "gl", "--aa", "1")) == 0
    assert json.loads(capsys.readouterr().out)["aa"] == 1
    on, off = np.load(tmp_path / "on.npy"), np.load(tmp_path / "off.npy")
    background = off[0, 0]
    sphere_off = np.any(np.abs(off - background) > 1e-4, axis=-1)
    # the silhouette is softened: pixels just outside the sphere take some of its colour
    outside_changed = np.any(np.abs(on - background) > 1e-3, axis=-1) & ~sphere_off
    assert outside_changed.sum() >= 8
    # the frame far from the silhouette is unchanged (background exactly, the centre within shading)
    np.testing.assert_allclose(on[0], off[0], atol=1e-6)
    np.testing.assert_allclose(on[12, 12], off[12, 12], rtol=0.02)


@pytest.mark.parametrize(("aa", "engine", "field"), [("3", "gl", "aa"), ("4", "numpy", "engine")])
def test_render_aa_refusals_exit_2(design, tmp_path, capsys, aa, engine, field):
    if engine == "gl":
        from station.render.gl_context import gl_available

        if not gl_available():
            pytest.skip("no GL context")
    rc = main(_args(design, tmp_path, "x", "--engine", engine, "--aa", aa))
    assert rc == 2
    assert capsys.readouterr().err.startswith(f"error: {field}")
