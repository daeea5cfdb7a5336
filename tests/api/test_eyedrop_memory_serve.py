"""The issue's bar against a real ``station serve``: 16 concurrent eyedrops of a 16 KB, 4-megapixel PNG
stay within 300 MiB of peak RSS above idle (``bench.eyedrop_memory`` measures and reports it)."""

from __future__ import annotations

import sys

import pytest

from bench.eyedrop_memory import BAR_MIB, board_png, measure


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/<pid>/status")
def test_sixteen_concurrent_eyedrops_stay_under_the_bar() -> None:
    png = board_png()
    assert len(png) < 32_000
    got = measure(2, png)
    assert got["peak_mib"] <= BAR_MIB, got
    # one 4-megapixel upload is decoded at 3 bytes a pixel (≈ 11 MiB) plus Pillow's buffers: far from
    # the ≈ 92 MiB a float64 decode alone needs
    assert got["single_mib"] < 92, got
