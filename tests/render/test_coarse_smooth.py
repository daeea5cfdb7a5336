"""The smooth terms at a coarser rate (``GLRenderer.coarse_smooth``, station.render.gl_passes): where the
sphere's footprint has an inside and both paints' wide-lobe weights agree, the wide lobes and their exact
lights are shaded once per k² pixels (k from ``coarse_factor``, calibrated by ``bench.coarse`` to stay within
0.1 ΔE00) and read back bilinearly. Held against the same renderer shading them at every pixel (the
reference: the per-pixel path) on frames outside the calibration set: other exponents, a frame whose sides
are not multiples of k, cameras near and far, the stage, the coat and the flakes, anti-aliasing; and the
geometry the read relies on, every coarse sample of every inside pixel hits the sphere, against the NumPy
ray caster."""

from __future__ import annotations

import numpy as np
import pytest

from bench.coarse import max_de, paint
from station.model.flakes import METALLIC_FLAKES
from station.model.gloss import ClearCoat
from station.render import footprint as fp
from station.render import prefilter, procedural, shapes
from station.render.camera import orbit_camera
from station.render.gl_passes import COARSE_FACTORS, COARSE_MIN_NDV, coarse_inner_margin_px
from station.render.stage import Stage

W, H = 601, 457  # not multiples of the factor
#: Two bases outside the calibration set's: wide lobes up to 40 (k 2 in these views) and up to 20 (k 4).
BASES = {"wide-40": (3.0, 12.0, 40.0, 400.0), "wide-20": (2.5, 6.0, 20.0, 800.0)}
CAMERAS = [
    None,  # the sphere's default view
    orbit_camera((0.0, 0.0, 0.0), 35.0, 20.0, 3.0, fov_deg=40.0),  # close: the sphere fills most of the frame
    orbit_camera((0.0, 0.0, 0.0), 200.0, -15.0, 6.0, fov_deg=30.0),  # far
]
#: ΔE00 bound of the coarse frame against the per-pixel one (Lab relative to the frame's brightest pixel): the
#: calibration's 0.1 (bench.coarse), with half of it again for frames it did not see.
MAX_DE = 0.15


@pytest.fixture(scope="module")
def bases(gl_ctx):
    """A sky with a sun (exact lights on the wide lobes, the sharpest smooth term), prefiltered for BASES."""
    env = procedural.procedural_environment("sky", 128)
    return {name: prefilter.prefilter_basis(env, exps, ctx=gl_ctx) for name, exps in BASES.items()}


@pytest.fixture(scope="module")
def basis(bases):
    return bases["wide-40"]


@pytest.mark.gl
@pytest.mark.parametrize(
    ("name", "stage", "coat", "flakes", "aa", "factor"),
    [
        ("wide-40", False, False, False, 1, 2),
        ("wide-40", True, True, True, 4, 4),  # at twice the shading size: k 4
        ("wide-20", False, False, False, 1, 4),
        ("wide-20", True, True, True, 1, 4),
    ],
)
def test_coarse_frame_matches_the_per_pixel_frame(
    gl_ctx, bases, name, stage, coat, flakes, aa, factor
) -> None:
    from station.render.gl_renderer import GLRenderer

    paints = [paint(BASES[name], 0.3), paint(BASES[name], 0.3)]
    layer = ClearCoat() if coat else None
    sparkle = METALLIC_FLAKES if flakes else None
    with GLRenderer(bases[name], W, H, ctx=gl_ctx, aa=aa) as gl:
        for i, cam in enumerate(CAMERAS):
            scene = shapes.Scene("sphere", camera=cam, stage=Stage() if stage else None)
            frames, bytes_, used = [], [], []
            for coarse in (False, True):
                gl.coarse_smooth = coarse
                frames.append(gl.render_linear(scene, paints, coat=layer, flakes=sparkle).astype(np.float64))
                used.append(gl.last_coarse)
                bytes_.append(gl.render(scene, paints, coat=layer, flakes=sparkle).astype(int))
            assert used[0] == 0
            if i == 0:  # the default view: the factor the calibration gives there
                assert used[1] == factor
            full, coarse_frame = frames
            if used[1]:
                assert not np.array_equal(full, coarse_frame)  # the coarse path drew this frame
            de = max_de(full, coarse_frame)
            assert de < MAX_DE, (cam, used[1], de)
            assert np.abs(bytes_[0] - bytes_[1]).max() <= 1


@pytest.mark.gl
def test_two_paints_shade_at_every_pixel(gl_ctx, basis) -> None:
    """Two paints with other wide-lobe weights: the seam between them would be blurred, so no coarse pass."""
    from station.render.gl_renderer import GLRenderer

    paints = [paint(BASES["wide-40"], 0.3), paint(BASES["wide-40"], 0.1)]
    scene = shapes.Scene("sphere")
    with GLRenderer(basis, W, H, ctx=gl_ctx) as gl:
        on = gl.render_linear(scene, paints)
        assert gl.last_coarse == 0
        gl.coarse_smooth = False
        off = gl.render_linear(scene, paints)
    assert np.array_equal(on, off)


@pytest.mark.gl
def test_other_shapes_shade_at_every_pixel(gl_ctx, basis) -> None:
    """Only the sphere's footprint has an inside where every coarse sample hits."""
    from station.render.gl_renderer import GLRenderer

    with GLRenderer(basis, W, H, ctx=gl_ctx) as gl:
        gl.render_linear(shapes.Scene("speedshape"), [paint(BASES["wide-40"], 0.3)])
        assert gl.last_coarse == 0
        gl.render_linear(shapes.Scene("sphere"), [paint(BASES["wide-40"], 0.3)])
        assert gl.last_coarse == 2


@pytest.mark.parametrize("cam", range(len(CAMERAS)))
@pytest.mark.parametrize("size", [(W, H), (301, 203)])
@pytest.mark.parametrize("k", COARSE_FACTORS)
def test_every_coarse_sample_of_the_inside_hits(cam: int, size: tuple[int, int], k: int) -> None:
    """The four coarse samples a bilinear read at each inside pixel weights (the coarse pass's pixel
    centres around it, in the frame's normalised coordinates) all hit the sphere: NumPy's ray caster."""
    width, height = size
    scene = shapes.Scene("sphere", camera=CAMERAS[cam])
    foot = fp.shape_footprint(
        "sphere", scene.view_camera, width, height, 0.0, coarse_inner_margin_px(k), COARSE_MIN_NDV
    )
    assert foot is not None and foot.inner is not None
    cw, ch = -(-width // k), -(-height // k)
    # the inside pixels (NDC of their centres, y up)
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    y = 1.0 - 2.0 * (np.arange(height) + 0.5) / height
    ndc = np.stack(np.broadcast_arrays(x[None, :], y[:, None]), axis=-1)
    a, b = foot.inner, np.roll(foot.inner, -1, axis=0)
    cross = (b[:, 0] - a[:, 0]) * (ndc[..., None, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (
        ndc[..., None, 0] - a[:, 0]
    )
    inside = np.all(cross >= 0.0, axis=-1)
    assert inside.sum() > 1000
    # their bilinear reads: u = (column + 0.5) / width in texels of the coarse map, the four around it
    rows, cols = np.nonzero(inside)
    u = (cols + 0.5) / width * cw - 0.5
    v = (height - rows - 0.5) / height * ch - 0.5  # GL's rows from the bottom
    taps: set[tuple[int, int]] = set()
    for du in (0, 1):
        for dv in (0, 1):
            i = np.floor(u).astype(int) + du
            j = np.floor(v).astype(int) + dv
            taps.update(zip(i.tolist(), j.tolist(), strict=True))
    ti, tj = np.array(sorted(taps)).T
    # the coarse pass's rays: its pixel centres, a frame of cw x ch
    o, d = scene.view_camera.rays(cw, ch)
    hits = shapes.intersect(scene, o, d).mask  # (ch, cw), row 0 at the top
    assert np.all(hits[ch - 1 - tj, ti])
