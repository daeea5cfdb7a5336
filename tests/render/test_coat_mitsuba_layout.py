"""The equirect layout bench.coat_mitsuba hands to Mitsuba 3 (without Mitsuba: its documented mapping).

Mitsuba's ``envmap`` reads direction d at u = atan2(d_x, −d_z)/(2π) mod 1, v = arccos(d_y)/π (Mitsuba 3
source, ``emitters/envmap.cpp``); the product's equirect puts −Z at the centre column
(:mod:`station.render.cubemap`). The bench verifies the same with a rendered test scene when it runs.
"""

from __future__ import annotations

import numpy as np

from bench.coat_mitsuba import to_mitsuba
from station.render.cubemap import equirect_directions


def _mitsuba_uv(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    u = np.mod(np.arctan2(d[..., 0], -d[..., 2]) / (2.0 * np.pi), 1.0)
    return u, np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / np.pi


def test_rolled_map_puts_each_direction_where_mitsuba_reads_it() -> None:
    h, w = 16, 32
    dirs = equirect_directions(h, w)
    index = np.arange(h * w, dtype=np.float32).reshape(h, w)
    img = np.repeat(index[..., None], 3, axis=2)
    rolled = to_mitsuba(img)
    u, v = _mitsuba_uv(dirs)
    col = np.floor(u * w).astype(int) % w
    row = np.floor(v * h).astype(int)
    # Mitsuba reads the product's pixel (i, j) back at the rolled array's (row, col).
    np.testing.assert_array_equal(rolled[row, col, 0], index)


def test_unrolled_map_would_be_half_a_turn_off() -> None:
    h, w = 16, 32
    dirs = equirect_directions(h, w)
    u, _v = _mitsuba_uv(dirs)
    col = np.floor(u * w).astype(int) % w
    assert np.all(col != np.arange(w)[None, :])
