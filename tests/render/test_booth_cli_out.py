"""``station booth --out`` from a user's folder: the booth picture of a metameric pair under D65 and A."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from station.ingest.formats import write_measurement_file
from station.render.booth import BOOTH_SIZE
from tests.cli.test_booth_cli import _measurement, pair  # noqa: F401 - the module fixture
from tests.user_cli import run_station


def _picture(tmp_path: Path, sample: str, out: str) -> np.ndarray:
    run = run_station(
        tmp_path, "booth", "--standard", "standard.cxf", "--sample", sample,
        "--illuminants", "D65,A", "--shape", "panels", "--out", out, "--json",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    with Image.open(tmp_path / out) as im:
        return np.asarray(im.convert("RGB")).astype(int)


def test_out_draws_the_pair_matching_under_d65_and_not_under_a(tmp_path: Path, pair) -> None:  # noqa: F811
    std, smp = pair
    write_measurement_file([_measurement("standard", std)], tmp_path / "standard.cxf")
    write_measurement_file([_measurement("trial", smp)], tmp_path / "trial.cxf")
    alike = _picture(tmp_path, "standard.cxf", "alike.png")  # the standard against itself
    booth = _picture(tmp_path, "trial.cxf", "booth.png")
    assert booth.shape[1] == 2 * BOOTH_SIZE and booth.shape[0] > BOOTH_SIZE  # two tiles, captions below
    d65, a = (slice(0, BOOTH_SIZE), slice(0, BOOTH_SIZE)), (slice(0, BOOTH_SIZE), slice(BOOTH_SIZE, None))
    assert np.abs(booth[d65] - alike[d65]).max() <= 1  # metamers under D65: the same picture
    changed = np.abs(booth[a] - alike[a]).max(axis=2) >= 2  # under A the trial panel differs
    assert changed.mean() > 0.1 and not changed[:, : BOOTH_SIZE // 3].any()  # the standard's panel did not
    assert not np.array_equal(booth[d65], booth[a])  # the light's colour changed


def test_out_refuses_an_unwritable_path_in_one_line(tmp_path: Path, pair) -> None:  # noqa: F811
    std, _ = pair
    write_measurement_file([_measurement("standard", std)], tmp_path / "standard.cxf")
    run = run_station(
        tmp_path, "booth", "--standard", "standard.cxf", "--sample", "standard.cxf",
        "--out", "missing-folder/booth.png",
    )  # fmt: skip
    assert run.returncode == 2 and "out" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1, run.stderr
