"""The product's CIEDE2000 (station.model.cie2000, docs/adr/0006) tied to the published data and to colour-science.

The NumPy copy exists for speed (ADR 0006); these tests are what keeps it the same formula: Sharma, Wu &
Dalal's published pairs to their 4 decimals, and colour-science's ``delta_E`` on random pairs (grey,
hue-wrapping and L* > 100 pairs included) equal to 1e-9 — in practice bit for bit.
"""

from __future__ import annotations

import colour
import numpy as np
import pytest

from station.model.cie2000 import cie2000_columns
from station.model.difference import delta_e

# Sharma, Wu & Dalal (2005), "The CIEDE2000 color-difference formula: implementation notes, supplementary
# test data, and mathematical observations", Table 1: (Lab 1, Lab 2, ΔE00). Pair 14, (50, −0.001, 2.49) against
# (50, 0.001, −2.49), is left out, as in colour-science's own test: its h'₂ − h'₁ is 180° to within one ulp,
# and np.arctan2's last bit differs between platforms, which moves the result from the published 4.8045
# to 4.7461 on some of them.
SHARMA = [
    ((50.0000, 2.6772, -79.7751), (50.0000, 0.0000, -82.7485), 2.0425),
    ((50.0000, 3.1571, -77.2803), (50.0000, 0.0000, -82.7485), 2.8615),
    ((50.0000, 2.8361, -74.0200), (50.0000, 0.0000, -82.7485), 3.4412),
    ((50.0000, -1.3802, -84.2814), (50.0000, 0.0000, -82.7485), 1.0000),
    ((50.0000, -1.1848, -84.8006), (50.0000, 0.0000, -82.7485), 1.0000),
    ((50.0000, -0.9009, -85.5211), (50.0000, 0.0000, -82.7485), 1.0000),
    ((50.0000, 0.0000, 0.0000), (50.0000, -1.0000, 2.0000), 2.3669),
    ((50.0000, -1.0000, 2.0000), (50.0000, 0.0000, 0.0000), 2.3669),
    ((50.0000, 2.4900, -0.0010), (50.0000, -2.4900, 0.0009), 7.1792),
    ((50.0000, 2.4900, -0.0010), (50.0000, -2.4900, 0.0010), 7.1792),
    ((50.0000, 2.4900, -0.0010), (50.0000, -2.4900, 0.0011), 7.2195),
    ((50.0000, 2.4900, -0.0010), (50.0000, -2.4900, 0.0012), 7.2195),
    ((50.0000, -0.0010, 2.4900), (50.0000, 0.0009, -2.4900), 4.8045),
    ((50.0000, -0.0010, 2.4900), (50.0000, 0.0011, -2.4900), 4.7461),
    ((50.0000, 2.5000, 0.0000), (50.0000, 0.0000, -2.5000), 4.3065),
    ((50.0000, 2.5000, 0.0000), (73.0000, 25.0000, -18.0000), 27.1492),
    ((50.0000, 2.5000, 0.0000), (61.0000, -5.0000, 29.0000), 22.8977),
    ((50.0000, 2.5000, 0.0000), (56.0000, -27.0000, -3.0000), 31.9030),
    ((50.0000, 2.5000, 0.0000), (58.0000, 24.0000, 15.0000), 19.4535),
    ((50.0000, 2.5000, 0.0000), (50.0000, 3.1736, 0.5854), 1.0000),
    ((50.0000, 2.5000, 0.0000), (50.0000, 3.2972, 0.0000), 1.0000),
    ((50.0000, 2.5000, 0.0000), (50.0000, 1.8634, 0.5757), 1.0000),
    ((50.0000, 2.5000, 0.0000), (50.0000, 3.2592, 0.3350), 1.0000),
    ((60.2574, -34.0099, 36.2677), (60.4626, -34.1751, 39.4387), 1.2644),
    ((63.0109, -31.0961, -5.8663), (62.8187, -29.7946, -4.0864), 1.2630),
    ((61.2901, 3.7196, -5.3901), (61.4292, 2.2480, -4.9620), 1.8731),
    ((35.0831, -44.1164, 3.7933), (35.0232, -40.0716, 1.5901), 1.8645),
    ((22.7233, 20.0904, -46.6940), (23.0331, 14.9730, -42.5619), 2.0373),
    ((36.4612, 47.8580, 18.3852), (36.2715, 50.5065, 21.2231), 1.4146),
    ((90.8027, -2.0831, 1.4410), (91.1528, -1.6435, 0.0447), 1.4441),
    ((90.9257, -0.5406, -0.9208), (88.6381, -0.8985, -0.7239), 1.5381),
    ((6.7747, -0.2908, -2.4247), (5.8714, -0.0985, -2.2286), 0.6377),
    ((2.0776, 0.0795, -1.1350), (0.9033, -0.0636, -0.5514), 0.9082),
]


def _columns(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return cie2000_columns(a[..., 0], a[..., 1], a[..., 2], b[..., 0], b[..., 1], b[..., 2])


def test_sharma_2005_table_1() -> None:
    a = np.array([p[0] for p in SHARMA])
    b = np.array([p[1] for p in SHARMA])
    published = np.array([p[2] for p in SHARMA])
    # The table is rounded to 4 decimals: every value within half a unit of the last place.
    np.testing.assert_allclose(_columns(a, b), published, rtol=0, atol=5e-5)
    np.testing.assert_allclose(delta_e(a, b, "cie2000"), published, rtol=0, atol=5e-5)


def _random_pairs(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    n = 5000
    a = rng.uniform([0, -128, -128], [160, 128, 128], (n, 3))
    b = np.concatenate(
        [
            a[: n // 2] + rng.normal(0, 3, (n // 2, 3)),  # near pairs, as tolerances see them
            rng.uniform([0, -128, -128], [160, 128, 128], (n - n // 2, 3)),  # far pairs, across the hue wrap
        ]
    )
    a[::50, 1:] = 0.0  # greys on either side: the achromatic hue branch
    b[::70, 1:] = 0.0
    a[::97] = b[::97]  # identical colours: ΔE00 = 0
    return a, b


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_equals_colour_science_on_random_pairs(seed: int) -> None:
    a, b = _random_pairs(seed)
    expected = np.asarray(colour.delta_E(a, b, method="CIE 2000"), dtype=float)
    np.testing.assert_allclose(_columns(a, b), expected, rtol=0, atol=1e-9)
    # The same operations in the same order (the module docstring lists what was dropped): equal bit for bit.
    np.testing.assert_array_equal(_columns(a, b), expected)
    np.testing.assert_allclose(delta_e(a, b, "cie2000"), expected, rtol=0, atol=1e-9)
    # Swapping reference and sample gives the same difference (the formula is symmetric in exact arithmetic).
    np.testing.assert_allclose(_columns(b, a), expected, rtol=0, atol=1e-9)
    assert np.all(_columns(a[::97], a[::97]) == 0.0)


def test_broadcasts_one_reference_against_many_samples() -> None:
    ref = np.array([50.0, 2.5, 0.0])
    samples = np.array([p[1] for p in SHARMA[15:23]])
    got = cie2000_columns(ref[0], ref[1], ref[2], samples[:, 0], samples[:, 1], samples[:, 2])
    expected = colour.delta_E(np.broadcast_to(ref, samples.shape), samples, method="CIE 2000")
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)
