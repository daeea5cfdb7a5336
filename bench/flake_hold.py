"""Whether the flakes hold: the mean colour and the sparkle's stability, per view and environment.

The silver of ``tests/render/test_flakes_surface.py`` with the aluminium defaults on the speed shape, GL
renderer at 128², in the booth and the sunny sky, three views:

* ``default``: the speed shape's own camera;
* ``close-up``: the close-up of docs/render.md (``bench.render_scene.SHAPE_CLOSE``, the surface about
  0.6 units = 60 mm from the eye);
* ``macro``: the close-up of the surface tests (``CLOSE``: its target is 0.61 units away, but the eye is
  0.097 units = 9.7 mm from the surface it sees, where a pixel is 27 µm, about one flake, and a 16 × 16
  block holds about 75 flakes; a 0.25° turn about the target moves the view at that surface by ≈ 15° and
  a 0.2 % dolly changes its distance by ≈ 12 %).

Per case: p95 and max CIEDE2000 between 16 × 16-pixel means flakes on and off (the bar is p95 ≤ 0.5), and
the correlation of the sparkle at the same surface points after a 0.25° turn and a 0.2 % dolly (the
bar is ≥ 0.8). Prints one line per case; nothing is written.

Run: ``.venv/bin/python -m bench.flake_hold`` (EGL; a few seconds on llvmpipe).
"""

from __future__ import annotations

import numpy as np

from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.model.flakes import METALLIC_FLAKES
from station.render import prefilter, procedural, shapes
from station.render.camera import Camera
from station.render.gl_renderer import GLRenderer
from station.render.lobe_fit import fit_design
from tests.render.test_flakes_surface import CLOSE, SILVER, SIZE, _dolly, _orbit, _reprojected_correlation

#: The close-up of docs/render.md (bench.render_scene.SHAPE_CLOSE).
SHAPE_CLOSE = Camera((0.6, 0.35, 1.2), (0.3, 0.0, 0.0), fov_deg=30.0)
BLOCK = 16


def block_de(on: np.ndarray, off: np.ndarray) -> np.ndarray:
    """CIEDE2000 between the BLOCK × BLOCK-pixel means of two linear sRGB frames (H, W, 3)."""
    h, w = on.shape[0] // BLOCK, on.shape[1] // BLOCK

    def means(img: np.ndarray) -> np.ndarray:
        return img.reshape(h, BLOCK, w, BLOCK, 3).mean(axis=(1, 3)).reshape(-1, 3)

    return np.asarray(
        delta_e(linear_srgb_to_lab(means(on)), linear_srgb_to_lab(means(off)), method="cie2000")
    )


def main() -> None:
    w = fit_design(SILVER)
    views = (("default", shapes.Scene("speedshape").view_camera), ("close-up", SHAPE_CLOSE), ("macro", CLOSE))
    for env_name, env in (("booth", procedural.light_booth(128)), ("sky", procedural.sunny_sky(128))):
        basis = prefilter.prefilter_basis(env, w.exponents, max_size=64)
        with GLRenderer(basis, SIZE, SIZE) as gl:

            def sparkle(scene: shapes.Scene) -> tuple[np.ndarray, np.ndarray]:
                on = gl.render_linear(scene, [w], flakes=METALLIC_FLAKES).astype(float)
                return on, on - gl.render_linear(scene, [w]).astype(float)

            for view, cam in views:
                s0 = shapes.Scene("speedshape", camera=cam)
                on, sp0 = sparkle(s0)
                de = block_de(on, on - sp0)
                corr = []
                for moved in (_orbit(cam, 0.25), _dolly(cam, 1.002)):
                    s1 = shapes.Scene("speedshape", camera=moved)
                    corr.append(_reprojected_correlation(s0, s1, sp0, sparkle(s1)[1]))
                print(
                    f"{env_name:6s} {view:9s} block means p95 {np.percentile(de, 95):6.2f} "
                    f"max {de.max():6.2f} ΔE00; correlation turn {corr[0]:.3f} dolly {corr[1]:.3f}",
                    flush=True,
                )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "flake_hold")
    main()
