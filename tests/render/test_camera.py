"""The camera's small-vector cross product: the bits of ``np.cross``, which the frame's uniforms and the
shape's screen footprint were computed with before (so frames are unchanged)."""

from __future__ import annotations

import numpy as np

from station.render.camera import Camera, cross3


def test_cross3_is_numpys_cross_bit_for_bit() -> None:
    rng = np.random.default_rng(11)
    a, b = rng.normal(size=(2, 5000, 3)) * rng.choice([1e-8, 1.0, 1e8], size=(2, 5000, 1))
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(cross3(x, y), np.cross(x, y))
    assert np.array_equal(cross3((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), [0.0, 0.0, 1.0])


def test_basis_is_right_handed_and_orthonormal() -> None:
    f, r, u = Camera(eye=(0.3, 0.8, 4.5), target=(0.1, 0.0, -0.2)).basis()
    assert np.allclose(np.linalg.norm([f, r, u], axis=1), 1.0)
    assert np.allclose([f @ r, f @ u, r @ u], 0.0, atol=1e-15)
    assert np.allclose(np.cross(r, u), -f)  # right × up = backwards: x right, y up, z towards the eye
    assert r[1] == 0.0  # no roll: right stays horizontal with the default up
