"""Cached basis images: for a fixed view the rendered image is linear in the weights.

For a fixed scene and camera, every object pixel p (paint k) is (numpy_renderer's equation)

    rgb_p = w_D ⊙ D_p + w_A ⊙ A_p + Σ_i (h_i(c_p) w_G,i ⊙ C_i,p + g_i(c_p) w_DD,i ⊙ C_i(B_i,p)),    c_p = N·V,

(B_i = R for narrow lobes, the bent direction of ``numpy_renderer.dd_direction`` for wide ones; A_p the
aspecular fall-off correction ``numpy_renderer.fall_off_term`` with weight w_A = π K_A; w_D = π (K_D + K_A)),

so caching per-pixel images turns a paint edit into a small weighted sum. The images are D (diffuse
map at N); A (the fall-off term, computed with NumPy also when the other images come from GL); for each wide lobe (horizon table) h_i·C_i and g_i·C_i; for each narrow lobe
(g = c, h = 1) C_i alone, its directionally diffuse part weighted by the cached c. Per channel that is
a (2 × K) · (K × P) matrix product (K images, P object pixels, BLAS), then tone mapping and sRGB encoding
by a 64 k-entry lookup table, then a scatter into the cached frame (background pre-encoded). The edit runs
in blocks of ``EDIT_CHUNK`` pixels so that each block's panel and intermediates stay in cache: the images
are read once per edit. Pixels are stored grouped by paint, so each paint's pixels are one contiguous
slice. Images are float32: half storage would halve the bytes read, but NumPy's float16 → float32
conversion costs more than it saves (2× the CPU time per edit, measured at 1024²), and BLAS has no float16
GEMM.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from station.model.gloss import ClearCoat
from station.render import tonemap
from station.render.cubemap import sample_cube
from station.render.errors import RenderError, RenderInputError
from station.render.numpy_renderer import (
    BACKGROUND,
    check_paints,
    dd_direction,
    fall_off_term,
    gbuffer,
    horizon_table,
    light_terms,
    lobe_factors,
    stage_background,
)
from station.render.prefilter import WIDE_EXPONENT, PrefilteredBasis, coat_diffuse_map
from station.render.shapes import Scene, intersect
from station.render.stage import lookup_matrix
from station.render.weights import LobeWeights

if TYPE_CHECKING:
    from station.render.gl_renderer import GLRenderer

#: Pixels per block of a paint edit (:meth:`BasisImages.edit_rgba`): a (K, n) float32 panel of ~0.6 MB for
#: K = 9 fits the L2 cache, so the images are read once from memory (bench/viewer.py; 3.5× fewer CPU-ms
#: than one GEMM over all pixels at 1024²).
EDIT_CHUNK = 16384


@dataclass(eq=False)
class BasisImages:
    """Per-pixel basis images of one view (see module doc)."""

    basis: PrefilteredBasis
    width: int
    height: int
    pixels: np.ndarray  # (P,) flat indices of object pixels, paint 0 first
    split: int  # pixels[:split] carry paint 0, pixels[split:] paint 1
    images: np.ndarray  # (3, K, P) float32: channel, image (see layout), pixel
    n_dot_v: np.ndarray  # (P,) float32
    # ("D", -1) | ("A", -1) | ("Gh", i) | ("Dg", i) | ("C", i) per image; with a clear coat ("Cg", i) s·C_i (gloss) and
    # ("Cd", i) C_i (directionally diffuse, times c) replace ("C", i), and the Gh images hold s·h_i·C_i.
    layout: tuple[tuple[str, int], ...] = ()
    #: (H·W, 3) linear radiance behind the object when the scene has a stage (backdrop, ground), else None.
    background: np.ndarray | None = field(default=None, repr=False)
    _lut_key: tuple = field(default=(), repr=False)
    _lut: np.ndarray | None = field(default=None, repr=False)
    _scale: float = field(default=1.0, repr=False)
    _work: tuple | None = field(default=None, repr=False)

    @property
    def nbytes(self) -> int:
        """Bytes read by one paint edit (the images and N·V)."""
        return int(self.images.nbytes + self.n_dot_v.nbytes)

    def _weight_rows(self, paint: LobeWeights) -> np.ndarray:
        """(3, 2, K): per channel, row 0 = constant weights [w_D, w_A, w_G], row 1 = weights × c [0, w_DD]."""
        w_d, w_dd, w_g = paint.map_weights()
        rows = np.zeros((3, 2, len(self.layout)), np.float32)
        for j, (kind, i) in enumerate(self.layout):
            if kind == "D":
                rows[:, 0, j] = w_d
            elif kind == "A":
                rows[:, 0, j] = paint.fall_off_map_weight()
            elif kind == "Gh":
                rows[:, 0, j] = w_g[i]
            elif kind == "Dg":
                rows[:, 0, j] = w_dd[i]
            elif kind == "Cg":
                rows[:, 0, j] = w_g[i]
            elif kind == "Cd":
                rows[:, 1, j] = w_dd[i]
            elif kind == "B":
                rows[:, 0, j] = 1.0  # the background share of an anti-aliased edge pixel
            else:
                rows[:, 0, j] = w_g[i]
                rows[:, 1, j] = w_dd[i]
        return rows

    def linear(self, paints: Sequence[LobeWeights]) -> np.ndarray:
        """Radiance of the object pixels, (3, P) float32, for one or two paints."""
        pair = check_paints(self.basis, paints)
        out = np.empty((3, self.pixels.size), np.float32)
        for k, sl in ((0, slice(0, self.split)), (1, slice(self.split, None))):
            rows = self._weight_rows(pair[k])
            ndv = self.n_dot_v[sl]
            for c in range(3):
                ab = rows[c] @ self.images[c, :, sl]  # (2, P_k), one BLAS call
                out[c, sl] = ab[0] + ndv * ab[1]
        return out

    def linear_image(self, paints: Sequence[LobeWeights]) -> np.ndarray:
        """Full linear frame (H, W, 3) float32 with the background."""
        img = (
            np.full((self.height * self.width, 3), BACKGROUND, np.float32)
            if self.background is None
            else self.background.astype(np.float32).copy()
        )
        img[self.pixels] = self.linear(paints).T
        return img.reshape(self.height, self.width, 3)

    def _prepare(self, exposure_ev: float, curve: str) -> None:
        key = (float(exposure_ev), curve)
        if key == self._lut_key:
            return
        lut, self._scale = tonemap.display_lut(exposure_ev, curve)
        lut32 = lut.astype(np.uint32)
        # One table per channel, already shifted into its byte of an RGBA8 word (little-endian), alpha set.
        self._lut = np.stack([lut32, lut32 << 8, (lut32 << 16) | np.uint32(0xFF000000)])
        if self.background is None:
            bg = tonemap.to_display(np.array([BACKGROUND] * 3), exposure_ev, curve).astype(np.uint32)
            self._bg32 = np.asarray(bg[0] | (bg[1] << 8) | (bg[2] << 16) | 0xFF000000, np.uint32)
        else:  # the stage: one pre-encoded word per pixel
            bg = tonemap.to_display(self.background.astype(np.float32), exposure_ev, curve).astype(np.uint32)
            self._bg32 = np.asarray(bg[:, 0] | (bg[:, 1] << 8) | (bg[:, 2] << 16) | 0xFF000000, np.uint32)
        self._lut_key = key

    def edit_rgba(
        self,
        paints: Sequence[LobeWeights],
        exposure_ev: float = 0.0,
        curve: str = "aces",
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Tone-mapped 8-bit sRGB frame (H, W, 4) RGBA for new weights: the fast path of a paint edit.

        The exposure and LUT scale are folded into the weights, so the BLAS product yields LUT indices
        directly; the per-channel tables return pre-shifted bytes OR-ed into one 32-bit word per pixel,
        which is scattered into the frame once. Pass *out* (H, W, 4) uint8 to reuse a frame buffer
        (its background must come from an earlier call with the same exposure and curve).
        """
        self._prepare(exposure_ev, curve)
        pair = check_paints(self.basis, paints)
        if out is None:
            out = np.empty((self.height, self.width, 4), np.uint8)
            out.reshape(-1).view(np.uint32)[:] = self._bg32
        frame = out.reshape(-1).view(np.uint32)
        if self._work is None:  # scratch buffers, reused: fresh large arrays cost page faults each edit
            n = self.pixels.size
            self._work = (
                [np.empty((3, 2, EDIT_CHUNK), np.float32)],
                np.empty((3, EDIT_CHUNK), np.int32),
                np.empty(EDIT_CHUNK, np.uint32),
                np.empty(n, np.uint32),
            )
            from threadpoolctl import ThreadpoolController

            self._blas = ThreadpoolController()
        ab_pair, idx_all, code_all, packed = self._work
        scale = np.float32(self._scale)
        # K is tiny (m + 2 to 2m + 2): the product is memory-bound, and BLAS threads only add spin-wait jitter.
        with self._blas.limit(limits=1, user_api="blas"):
            self._combine(pair, scale, ab_pair, idx_all, code_all, packed)
        frame[self.pixels] = packed
        return out

    def _combine(
        self,
        pair: list[LobeWeights],
        scale: np.float32,
        ab_pair: list[np.ndarray],
        idx_all: np.ndarray,
        code_all: np.ndarray,
        packed: np.ndarray,
    ) -> None:
        lut = self._lut
        if lut is None:
            raise RenderError("basis images: tone-mapping table used before _prepare built it")
        n = EDIT_CHUNK
        ab, idx, code = ab_pair[0], idx_all, code_all
        for k, (a, b) in enumerate(((0, self.split), (self.split, self.pixels.size))):
            rows = self._weight_rows(pair[k]) * scale
            # Pixel blocks of EDIT_CHUNK: each block's (K, n) panel and every intermediate stay in cache
            # (one GEMM over all P pixels packs the whole panel and reads the images about three times).
            for p0 in range(a, b, n):
                p1 = min(b, p0 + n)
                m = p1 - p0
                o, ix, cd, dest = ab[:, :, :m], idx[:, :m], code[:m], packed[p0:p1]
                for c in range(3):
                    np.matmul(rows[c], self.images[c, :, p0:p1], out=o[c])
                np.multiply(o[:, 1], self.n_dot_v[p0:p1], out=o[:, 1])
                np.add(o[:, 0], o[:, 1], out=o[:, 0])
                np.copyto(ix, o[:, 0], casting="unsafe")
                lut[0].take(ix[0], mode="clip", out=dest)
                for c in (1, 2):
                    lut[c].take(ix[c], mode="clip", out=cd)
                    np.bitwise_or(dest, cd, out=dest)

    def edit(
        self, paints: Sequence[LobeWeights], exposure_ev: float = 0.0, curve: str = "aces"
    ) -> np.ndarray:
        """Tone-mapped 8-bit sRGB frame (H, W, 3) for new weights (a view of :meth:`edit_rgba`)."""
        return self.edit_rgba(paints, exposure_ev, curve)[..., :3]


def image_layout(
    exponents: Sequence[float], horizon: str = "lut", coat: bool = False
) -> tuple[tuple[str, int], ...]:
    """The cached images of a basis: D, A (the aspecular fall-off), then per lobe (Gh, Dg) when wide, (C,)
    when narrow ((Cg, Cd) with a clear coat, whose per-pixel gloss factor the shared C image cannot carry)."""
    table = horizon_table(exponents, horizon)
    c = np.linspace(0.0, 1.0, table.shape[1])
    layout: list[tuple[str, int]] = [("D", -1), ("A", -1)]
    for i, e in enumerate(exponents):
        exact = np.allclose(table[i, :, 0], c) and np.allclose(table[i, :, 1], 1.0)
        if exact and e >= WIDE_EXPONENT:
            layout += [("Cg", i), ("Cd", i)] if coat else [("C", i)]
        else:
            layout += [("Gh", i), ("Dg", i)]
    return tuple(layout)


def _lookup_images(
    basis: PrefilteredBasis,
    layout: tuple[tuple[str, int], ...],
    normals: np.ndarray,
    refl: np.ndarray,
    ndv: np.ndarray,
    horizon: str,
    coat: ClearCoat | None,
    gl_images: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(images (3, K, P), fall-off (3, P), coat gloss factor s (P,), coat base factor 1 − F (P,)) of object
    points with unit *normals* and reflected views *refl* (P, 3, in the environment's frame) and N·V *ndv*
    (P,). With *gl_images* only the fall-off and factors are computed (the GL renderer makes the rest)."""
    d_normal = sample_cube(basis.diffuse, normals)
    fall_off = fall_off_term(
        basis, normals, refl, ndv.astype(np.float64), horizon=horizon, d_normal=d_normal
    ).T
    d_image = d_normal
    if coat is not None:
        # the D image (weight π(K_D + K_A)) reads the coat-transmitted map, the A image (weight π K_A)
        # carries K_A's share back to D: π K_D D_coat + π K_A (D + fall-off), as numpy_renderer.shade_pixels
        d_image = sample_cube(coat_diffuse_map(basis, coat), normals)
        fall_off = fall_off + (d_normal - d_image).T
    # the coat's factors on the gloss and the base images (numpy_renderer.shade_pixels); ones without it
    sc = np.ones_like(ndv) if coat is None else coat.gloss_scale(ndv).astype(np.float32)
    tb = np.ones_like(ndv) if coat is None else coat.base_scale(ndv).astype(np.float32)
    images = np.zeros((3, len(layout), ndv.size), np.float32)
    if gl_images:
        return images, fall_off, sc, tb
    gf, hf = lobe_factors(horizon_table(basis.exponents, horizon), ndv)
    lookups: dict[int, np.ndarray] = {}
    for j, (kind, i) in enumerate(layout):
        if kind == "D":
            images[:, j] = d_image.T * tb
            continue
        if kind == "A":
            images[:, j] = fall_off * tb
            continue
        if kind == "B":  # the background share of an anti-aliased edge pixel: set by the resolve
            continue
        if i not in lookups:
            lookups[i] = sample_cube(basis.cubes[i], refl).T
        bent = dd_direction(basis.exponents[i], normals, refl, horizon) if kind == "Dg" else None
        lookup = lookups[i] if bent is None else sample_cube(basis.cubes[i], bent).T
        factor = {"Gh": hf[:, i] * sc, "Dg": gf[:, i] * tb, "Cg": sc}.get(kind, tb)
        images[:, j] = lookup * factor
        lights = light_terms(basis, i, normals, refl) if kind in ("Gh", "Dg") else None
        if lights is not None:
            images[:, j] += (lights[0] * sc[:, None] if kind == "Gh" else lights[1] * tb[:, None]).T
    return images, fall_off, sc, tb


def edge_pixels(label: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels whose label (paint id, −1 off the object) differs from one of their 8
    neighbours' — every pixel a silhouette or a paint seam can cross, given a shape no thinner than a
    pixel."""
    pad = np.pad(label, 1, mode="edge")
    h, w = label.shape
    edge = np.zeros(label.shape, bool)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            if dy != 1 or dx != 1:
                edge |= pad[dy : dy + h, dx : dx + w] != label
    return edge


@dataclass(frozen=True)
class _EdgeResolve:
    """Edge pixels resolved from s × s subsamples (:func:`_resolve_edges`): flat pixel indices (E,), paint
    (E,) (the majority of the covered subsamples, −1 when none), the object's images summed over covered
    subsamples / s² (3, K, E), mean N·V of the covered subsamples (E,), and the background radiance summed
    over uncovered subsamples / s² (E, 3)."""

    pixels: np.ndarray
    paint: np.ndarray
    images: np.ndarray
    n_dot_v: np.ndarray
    background: np.ndarray


def _resolve_edges(
    scene: Scene,
    basis: PrefilteredBasis,
    layout: tuple[tuple[str, int], ...],
    width: int,
    height: int,
    edge: np.ndarray,
    side: int,
    horizon: str,
    coat: ClearCoat | None,
    rot: np.ndarray,
) -> _EdgeResolve:
    """Ray-cast the *side* × *side* grid of subsamples of each edge pixel and box-resolve them."""
    idx = np.flatnonzero(edge.reshape(-1))
    py, px = np.divmod(idx, width)
    offs = (np.arange(side) + 0.5) / side
    shape = (idx.size, side, side)  # subsample (pixel, row, column)
    sx = np.broadcast_to(px[:, None, None] + offs[None, None, :], shape).reshape(-1)  # x (pixels)
    sy = np.broadcast_to(py[:, None, None] + offs[None, :, None], shape).reshape(-1)
    cam = scene.view_camera
    f, r, u = cam.basis()
    t = np.tan(np.radians(cam.fov_deg) / 2.0)
    x = (2.0 * sx / width - 1.0) * t * width / height  # Camera.rays at sub-pixel positions
    y = (1.0 - 2.0 * sy / height) * t
    d = f[None, :] + x[:, None] * r[None, :] + y[:, None] * u[None, :]
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    origin = np.asarray(cam.eye, dtype=np.float64)
    hits = intersect(scene, origin, d)
    hit = hits.mask.reshape(-1)
    n = hits.normal.reshape(-1, 3)[hit]
    v = -d[hit]
    ndv_s = np.sum(n * v, axis=-1)
    refl = 2.0 * ndv_s[:, None] * n - v
    ndv_s = np.clip(ndv_s, 0.0, 1.0).astype(np.float32)  # as gbuffer's N·V for the cached c
    imgs, *_ = _lookup_images(basis, layout, n @ rot.T, refl @ rot.T, ndv_s, horizon, coat)
    e, s2 = idx.size, side * side
    owner = np.repeat(np.arange(e), s2)
    o_hit = owner[hit]
    count = np.bincount(o_hit, minlength=e)
    images = np.empty((3, len(layout), e), np.float32)
    for c in range(3):
        for j in range(len(layout)):
            images[c, j] = np.bincount(o_hit, imgs[c, j], minlength=e) / s2
    ndv = np.bincount(o_hit, ndv_s, minlength=e) / np.maximum(count, 1)
    ones = np.bincount(o_hit, hits.paint.reshape(-1)[hit] == 1, minlength=e)
    paint = np.where(count == 0, -1, (2 * ones > count).astype(np.int8)).astype(np.int8)
    miss = ~hit
    bg = np.full((d.shape[0], 3), BACKGROUND, np.float64)
    if scene.stage is not None and miss.any():
        # the ground shadowed by the shape itself, as the viewer's GL frames before these images shade it
        # (GLRenderer.object_shadows False: the maps in the ground's bake only)
        bg[miss] = stage_background(scene, basis, origin, d[miss])
    bg[hit] = 0.0
    background = np.stack([np.bincount(owner, bg[:, c], minlength=e) for c in range(3)], axis=-1) / s2
    return _EdgeResolve(idx, paint, images, ndv.astype(np.float32), background.astype(np.float32))


def _gl_images(
    images: NDArray[np.float32],
    scene: Scene,
    basis: PrefilteredBasis,
    layout: tuple[tuple[str, int], ...],
    gl_renderer: GLRenderer,
    coat: ClearCoat | None,
    pixels: NDArray[np.int64],
    fall_off: NDArray[np.float32],
    tb: NDArray[np.float32] | float,
) -> None:
    """Fill *images* (3, layout, pixels) with GL renders of one unit weight per layout entry: the base
    images times what the coat transmits (*tb*), the coat's gloss images as rendered, the fall-off image
    (``"A"``) as the NumPy path makes it (*fall_off*, already times *tb*)."""
    m = len(basis.exponents)
    e = np.array(basis.exponents)
    for j, (kind, i) in enumerate(layout):
        if kind == "A":  # one image, made by numpy_renderer.fall_off_term as on the NumPy path
            images[:, j] = fall_off
            continue
        k_d, k_dd, k_g = np.zeros(3), np.zeros((m, 3)), np.zeros(m)
        if kind == "D":
            k_d[:] = 1.0 / np.pi
        elif kind == "Dg":
            k_dd[i] = (e[i] + 1.0) / (2.0 * np.pi)
        else:
            k_g[i] = (e[i] + 1.0) / (2.0 * np.pi)
        unit = LobeWeights(basis.exponents, k_d, k_dd, k_g)
        unit_coat = coat if kind in ("Gh", "Cg", "D") else None  # "D": the coat-transmitted map
        images[:, j] = gl_renderer.render_linear(scene, [unit], coat=unit_coat).reshape(-1, 3)[pixels].T
        if unit_coat is None:
            images[:, j] *= tb  # a base image: what the coat transmits (1 when there is none)
        # (with a coat the "D" image is rendered with it: D_coat times 1 − F, as the NumPy path makes it)


def build_basis_images(
    scene: Scene,
    basis: PrefilteredBasis,
    width: int,
    height: int,
    gl_renderer: GLRenderer | None = None,
    horizon: str = "lut",
    coat: ClearCoat | None = None,
    aa: int = 1,
) -> BasisImages:
    """Render the basis images of one view (NumPy lookups, or GL when a GLRenderer is given).

    A GL renderer must have been made with the same *horizon* setting. *coat*: the clear coat's Fresnel
    factors folded in: s(N·V) into the gloss images, 1 − F(N·V) into the base images (``numpy_renderer``'s
    equation with a coat).

    *aa*: anti-aliasing, samples per pixel (:data:`station.render.gl_targets.AA_SAMPLES`; NumPy lookups
    only). With s² = *aa* > 1 the pixels a silhouette or the paint seam can cross (:func:`edge_pixels`) are
    shaded at an s × s grid of subsamples and box-resolved in linear radiance, so an edge pixel holds
    coverage × the object's mean images plus the uncovered share of the background, the latter as one
    more image ``("B", -1)`` of weight 1 (the edit stays one weighted sum). The N·V an edge pixel's
    directionally diffuse term is multiplied by is its covered subsamples' mean. Other pixels are shaded
    once, at their centre (a paint's shading varies smoothly inside the silhouette): the cost is that of
    the edge pixels' subsamples only.
    """
    from station.render.gl_targets import AA_SAMPLES

    if isinstance(aa, bool) or aa not in AA_SAMPLES:
        raise RenderInputError("aa", " | ".join(str(a) for a in AA_SAMPLES) + " samples per pixel", aa)
    if aa > 1 and gl_renderer is not None:
        raise RenderInputError("aa", "1 with a GL renderer (it anti-aliases its own frames)", aa)
    g = gbuffer(scene, width, height)
    mask = g.mask.reshape(-1)
    paint = g.paint.reshape(-1).astype(np.int8)
    paint = np.where(mask, paint, -1).astype(np.int8)
    ndv_all = g.n_dot_v.reshape(-1).astype(np.float32)
    layout = image_layout(basis.exponents, horizon, coat is not None) + ((("B", -1),) if aa > 1 else ())
    rot = lookup_matrix(scene.stage.rotation_deg) if scene.stage is not None else np.eye(3)
    background = None
    if scene.stage is not None:
        origin, dirs = scene.view_camera.rays(width, height)
        background = np.zeros((width * height, 3), np.float32)
        miss = ~mask
        background[miss] = stage_background(scene, basis, origin, dirs.reshape(-1, 3)[miss])
    edges = None
    if aa > 1:
        edge = edge_pixels(paint.reshape(height, width))
        edges = _resolve_edges(scene, basis, layout, width, height, edge, math.isqrt(aa), horizon, coat, rot)
        mask = mask & ~edge.reshape(-1)  # the centre-shaded pixels; edge pixels come from the resolve
        paint = paint.copy()
        paint[edges.pixels] = edges.paint
        ndv_all = ndv_all.copy()
        ndv_all[edges.pixels] = edges.n_dot_v
        if background is not None:
            background[edges.pixels] = edges.background
    own = np.flatnonzero(mask)
    covered = np.flatnonzero(paint >= 0)
    pixels = np.concatenate([covered[paint[covered] == 0], covered[paint[covered] == 1]])
    split = int(np.count_nonzero(paint[covered] == 0))
    ndv = ndv_all[pixels]
    images = np.zeros((3, len(layout), pixels.size), np.float32)
    inner = np.isin(pixels, own, assume_unique=True)  # centre-shaded pixels' places in *pixels*
    normals = g.normal.reshape(-1, 3)[pixels[inner]] @ rot.T  # lookups in the environment's frame
    refl = g.reflect.reshape(-1, 3)[pixels[inner]] @ rot.T
    found, fall_off, _, tb = _lookup_images(
        basis, layout, normals, refl, ndv[inner], horizon, coat, gl_images=gl_renderer is not None
    )
    if gl_renderer is None:
        images[:, :, inner] = found
    else:
        _gl_images(images, scene, basis, layout, gl_renderer, coat, pixels, fall_off * tb, tb)
    if edges is not None:
        where = np.searchsorted(edges.pixels, pixels[~inner])  # edge pixels with some coverage
        images[:, :, ~inner] = edges.images[:, :, where]
        images[:, -1, ~inner] = edges.background[where].T
    return BasisImages(
        basis, width, height, pixels, split, np.ascontiguousarray(images), ndv, layout, background=background
    )
