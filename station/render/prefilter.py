"""Environment prefiltering with normalised Phong lobes, one cube map per exponent (thesis §2.5.1).

For exponent n the prefiltered map is

    P_n(R) = ∫_{R·ω>0} L(ω) · (n+1)/(2π) · (R·ω)^n dω,

the lobe normalised to integrate to 1 over the hemisphere around R, so a constant environment c gives
P_n = c for every n. P_1 is the diffuse map E(N)/π (thesis eq 2.5.3 prefilters with exponent 1); the
9-coefficient SH irradiance (:mod:`station.render.sh`) approximates the same thing.

Coat-transmitted diffuse map (:func:`coat_diffuse_map`): with a clear coat the diffuse base sees each
direction through the coat, so its map is

    D_coat(N) = (1/π) ∫ L(ω) t(N·ω) (N·ω)₊ dω,    t = (1 − F(N·ω; n))/(1 − F_dr,ext(n))

(``station.model.fresnel.ClearCoat.entry_scale``: Mitsuba's ``plastic``), prefiltered like the diffuse
map (the same brute-force sum, the entry weight on the radiance terms only, so a constant environment
c gives c, as t's cosine-weighted mean is 1).

Estimators of the same integral:

* :func:`prefilter_brute` — direct quadrature over every source texel with exact solid angles; the
  reference for tests, and the production path for wide lobes (output faces ≤ BRUTE_MAX_SIZE, from
  a source cube of max(32, 2× the output size)), where it has no sampling error; :class:`GLBrute` is
  its GL twin (same float32 terms) for the ``gl`` engine.
* the GL pass of :class:`GLPrefilter` and its NumPy twin :func:`prefilter_grid_numpy` (summed texel by
  texel in a numba-compiled loop, :mod:`station.render.prefilter_kernels`) —
  deterministic quadrature on a G×G tangent-plane grid around each texel direction covering the lobe
  down to cos^n = 1e-3, each sample read from the source mip level matching the grid step (see
  ``shaders/prefilter.frag.glsl``). Filtered importance sampling (Křivánek & Colbert 2008) was tried
  first: with bright small sources (studio softboxes, the sun) its error in the dark regions beside
  them was 20 % median against brute force at 512 samples; the grid quadrature is 1–2 % median at the
  same cost (measured figures in docs/render.md).

Output resolution follows the lobe width: the half-maximum angle θ½ = acos(2^(−1/n)) should span at
least ~1.6 texels, giving a face size of the next power of two ≥ 2.2·√n, clamped to [8, source size].
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from station.model.fresnel import ClearCoat
from station.render import cubemap
from station.render.envcache import PrefilterCache
from station.render.environment import Environment, Lights, extract_lights
from station.render.errors import RenderError, RenderInputError
from station.render.gl_context import build_program, create_gl_context, gl_available
from station.render.prefilter_kernels import compiled_kernels
from station.render.sh import sh_project

MAX_EXPONENT = 1.0e6
BRUTE_MAX_SIZE = 16
WIDE_EXPONENT = 200.0  # lobes below: horizon tables and lights shaded exactly (numpy_renderer)
OUTPUT_FACTOR = 2.2
DIFFUSE_SIZE = 16
DIFFUSE_SOURCE_SIZE = 32  # face size of the diffuse map's source cube
#: Face size of the coat-transmitted diffuse map and of its source cube: the entry weight falls to 0 at
#: grazing, so a light near a normal's horizon makes D_coat vary faster with the normal than D (a studio's
#: softboxes: 16-texel faces read 12 % high head-on against the map-integrated value, 32 within 3 %).
COAT_DIFFUSE_SIZE = 32
COAT_SOURCE_SIZE = 64
TABLE_STEPS = 65536


def check_exponent(exponent: float) -> float:
    """Validate one Phong exponent (1 ≤ n ≤ 1e6)."""
    e = float(exponent)
    if not (math.isfinite(e) and 1.0 <= e <= MAX_EXPONENT):
        raise RenderInputError("exponent", f"1 <= exponent <= {MAX_EXPONENT:.0e}", exponent)
    return e


def output_size(exponent: float, src_size: int) -> int:
    """Face size of the prefiltered map for exponent n: pow2 ≥ 2.2√n, within [8, src_size]."""
    want = OUTPUT_FACTOR * math.sqrt(exponent)
    size = 8
    while size < want and size < src_size:
        size *= 2
    return min(size, src_size)


def sample_count(out_size: int) -> int:
    """Quadrature grid side G (G² samples per texel): smaller for the large maps of narrow lobes."""
    return 24 if out_size <= 32 else 16 if out_size <= 64 else 10 if out_size <= 128 else 8


def source_size(env: Environment) -> int:
    """Source cube face size for an environment: width/4 (one texel ≈ one pixel at the equator), ≤ 512."""
    return int(min(512, max(8, 2 ** int(math.log2(env.equirect.shape[1] // 4)))))


def lobe_weights(dirs_out: np.ndarray, dirs_src: np.ndarray, exponent: float) -> np.ndarray:
    """(n+1)/(2π) max(0, R·ω)^n for every pair, (M, K)."""
    return _lobe_from_cosines((dirs_out @ dirs_src.T).astype(np.float32), exponent)


def _lobe_from_cosines(dots: np.ndarray, exponent: float) -> np.ndarray:
    """(n+1)/(2π) max(0, R·ω)^n from the float32 cosines R·ω (:func:`lobe_weights`' terms)."""
    cos = np.clip(dots, 1e-30, None)
    return np.float32((exponent + 1.0) / (2.0 * np.pi)) * np.exp(np.float32(exponent) * np.log(cos))


def prefilter_brute(
    src_cube: np.ndarray,
    exponent: float,
    out_size: int,
    coat: ClearCoat | None = None,
    compiled: bool = True,
) -> np.ndarray:
    """Reference prefilter by quadrature over all source texels, (6, out, out, 3) float64.

    Each texel counts with its exact solid angle; the sum is divided by the quadrature of the lobe
    itself (ideally 1), so a constant environment is reproduced exactly even when the lobe is
    narrower than a source texel. *coat*: weight each texel's radiance by the coat's entry weight
    t(R·ω) (module docstring; with exponent 1 the coat-transmitted diffuse map).

    *compiled*: sum output texel by output texel in float64 in the numba-compiled loop
    (:func:`station.render.prefilter_kernels.brute_sum`, the same float32 terms); False, or where numba
    cannot compile: float32 matrix products over blocks of 256 output texels (within 2e-5).
    """
    s = src_cube.shape[1]
    src_dirs = cubemap.face_directions(s).reshape(-1, 3)
    sa = np.tile(cubemap.texel_solid_angles(s).reshape(-1), 6)
    rad = np.concatenate([src_cube.reshape(-1, 3) * sa[:, None], sa[:, None]], axis=1).astype(np.float32)
    out_dirs = cubemap.face_directions(out_size).reshape(-1, 3)
    grid = np.linspace(0.0, 1.0, TABLE_STEPS + 1)
    table = (coat.entry_scale(grid) if coat is not None else grid).astype(np.float32)
    kernels = compiled_kernels() if compiled else None
    if kernels is not None:
        acc = kernels.brute(
            out_dirs, src_dirs, rad, float(exponent), table if coat is not None else table[:0]
        )
        return (acc[:, :3] / acc[:, 3:]).reshape(6, out_size, out_size, 3)
    out = np.empty((out_dirs.shape[0], 3))
    for i in range(0, out_dirs.shape[0], 256):
        dots = (out_dirs[i : i + 256] @ src_dirs.T).astype(np.float32)  # R·ω, once for w and t
        w = _lobe_from_cosines(dots, exponent)
        if coat is None:
            acc = w @ rad
        else:  # t(R·ω) from a fine table of the exact weight (nearest of 65537 steps: within 4e-5)
            c = np.clip(dots, 0.0, 1.0)
            t = table[(c * np.float32(TABLE_STEPS) + np.float32(0.5)).astype(np.int32)]
            acc = np.concatenate([(w * t) @ rad[:, :3], w @ rad[:, 3:]], axis=1)
        out[i : i + 256] = acc[:, :3] / acc[:, 3:]
    return out.reshape(6, out_size, out_size, 3)


class GLBrute:
    """:func:`prefilter_brute` as one GL pass per map (``shaders/prefilter_brute.frag.glsl``) on *ctx*:
    the same float32 terms as the NumPy version, so the maps agree to float rounding, ~50× faster on
    llvmpipe. Source cubes are uploaded once per object; a context manager (*ctx* is not released)."""

    def __init__(self, ctx) -> None:
        self.ctx = ctx
        self.prog = build_program(ctx, "fullscreen.vert.glsl", "prefilter_brute.frag.glsl")
        self.vao = ctx.vertex_array(self.prog, [])
        self._sources: dict[int, tuple[np.ndarray, Any, Any]] = {}

    def _texture(self, data: np.ndarray):
        """(6, S, S, C) float32 as an (S, 6S) float texture (faces stacked), nearest texel fetches."""
        s, c = data.shape[1], data.shape[-1]
        flat = np.ascontiguousarray(data.reshape(6 * s, s, c), dtype=np.float32)
        return self.ctx.texture((s, 6 * s), c, flat.tobytes(), dtype="f4")

    def run(
        self, src_cube: np.ndarray, exponent: float, out_size: int, coat: ClearCoat | None = None
    ) -> np.ndarray:
        """Prefiltered cube (6, out, out, 3) float32 (as :func:`prefilter_brute`, *coat* included)."""
        key = id(src_cube)
        if key not in self._sources:
            s = src_cube.shape[1]
            dirs = cubemap.face_directions(s).astype(np.float32)
            sa = np.tile(cubemap.texel_solid_angles(s), (6, 1, 1))[..., None].astype(np.float32)
            rad = np.concatenate([src_cube.astype(np.float32) * sa, sa], axis=-1)
            self._sources[key] = (src_cube, self._texture(dirs), self._texture(rad))  # keeps id valid
        _, src_dirs, src_rad = self._sources[key]
        out_dirs = self._texture(cubemap.face_directions(out_size))
        target = self.ctx.texture((out_size, 6 * out_size), 4, dtype="f4")
        fbo = self.ctx.framebuffer(color_attachments=[target])
        try:
            fbo.use()
            for unit, tex in enumerate((out_dirs, src_dirs, src_rad)):
                tex.use(unit)
            self.prog["u_out_dirs"] = 0
            self.prog["u_src_dirs"] = 1
            self.prog["u_src_rad"] = 2
            self.prog["u_exponent"] = float(exponent)
            self.prog["u_coat_n"] = 0.0 if coat is None else coat.index
            self.prog["u_coat_t"] = 1.0 if coat is None else coat.diffuse_transmission
            self.vao.render(mode=self.ctx.TRIANGLES, vertices=3)
            data = np.frombuffer(fbo.read(components=4, dtype="f4"), dtype=np.float32)
        finally:
            for obj in (fbo, target, out_dirs):
                obj.release()
        return data.reshape(6, out_size, out_size, 4)[..., :3].copy()

    def release(self) -> None:
        """Free the GL objects."""
        for _, a, b in self._sources.values():
            a.release()
            b.release()
        self._sources.clear()
        self.vao.release()
        self.prog.release()

    def __enter__(self) -> GLBrute:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


TAIL = 1.0e-3
MAX_LOBE_DEG = 75.0


def grid_parameters(exponent: float, grid: int, src_size: int) -> tuple[float, float]:
    """(u_max, mip level) of the tangent-grid quadrature: the grid covers cos^n ≥ TAIL (≤ 75°)."""
    theta = min(math.acos(TAIL ** (1.0 / exponent)), math.radians(MAX_LOBE_DEG))
    umax = math.tan(theta)
    h = 2.0 * umax / grid
    return umax, max(0.0, math.log2(h * src_size / 2.0))


def prefilter_grid_numpy(
    src_cube: np.ndarray, exponent: float, out_size: int, grid: int, compiled: bool = True
) -> np.ndarray:
    """The GL tangent-grid quadrature in NumPy (fallback where no GL context exists): faces
    (6, out_size, out_size, 3) float64 from *src_cube* (6, S, S, 3), *grid*² samples per texel.

    *compiled*: sum texel by texel in the numba-compiled loop (:mod:`station.render.prefilter_kernels`, the
    same sums to the last bit); False, or where numba cannot compile: the vectorised loop below."""
    mips = mip_chain(src_cube)
    umax, lod = grid_parameters(exponent, grid, src_cube.shape[1])
    lod = min(lod, len(mips) - 1)
    r = cubemap.face_directions(out_size).reshape(-1, 3)
    up = np.where(np.abs(r[:, 1:2]) < 0.999, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    t = np.cross(up, r)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = np.cross(r, t)
    h = 2.0 * umax / grid
    coords = -umax + (np.arange(grid) + 0.5) * h
    lo = int(math.floor(lod))
    frac = lod - lo
    blend = bool(frac > 0 and lo + 1 < len(mips))
    weights = np.array([[(1.0 + u * u + v * v) ** (-(exponent + 3.0) / 2.0) for u in coords] for v in coords])
    wsum = 0.0
    for w in weights.ravel():  # in the loop's order: the same rounding as summing along the way
        wsum += float(w)
    kernels = compiled_kernels() if compiled else None
    if kernels is not None:
        hi = mips[lo + 1] if blend else mips[lo]
        acc = kernels.grid(mips[lo], hi, frac, blend, r, t, b, coords, weights)
        return (acc / wsum).reshape(6, out_size, out_size, 3)
    acc = np.zeros_like(r)
    for j, v in enumerate(coords):
        for i, u in enumerate(coords):
            d = r + u * t + v * b
            val = cubemap.sample_cube(mips[lo], d)
            if blend:
                val = val * (1 - frac) + cubemap.sample_cube(mips[lo + 1], d) * frac
            acc += weights[j, i] * val
    return (acc / wsum).reshape(6, out_size, out_size, 3)


def mip_chain(cube: np.ndarray) -> list[np.ndarray]:
    """Box-filtered mip levels of a cube map down to 1×1 faces."""
    levels = [cube.astype(np.float32)]
    while levels[-1].shape[1] > 1:
        levels.append(cubemap.downsample_cube(levels[-1]))
    return levels


class GLPrefilter:
    """The GL tangent-grid quadrature pass for one source cube (module docstring); a context manager.

    Pass *ctx* to share a context (it is then not released here); otherwise one is created.
    """

    def __init__(self, src_cube: np.ndarray, ctx=None) -> None:
        self._own_ctx = ctx is None
        self.ctx = create_gl_context() if ctx is None else ctx
        self.src_size = int(src_cube.shape[1])
        self._upload(src_cube)
        self.prog = build_program(self.ctx, "fullscreen.vert.glsl", "prefilter.frag.glsl")
        self.vao = self.ctx.vertex_array(self.prog, [])

    @classmethod
    def from_equirect(cls, equirect: np.ndarray, size: int, ctx=None) -> GLPrefilter:
        """Build the source cube on the GPU from an equirect image (2×2 supersampled per texel)."""
        own = ctx is None
        ctx = create_gl_context() if own else ctx
        h, w = equirect.shape[:2]
        eq = ctx.texture((w, h), 3, np.ascontiguousarray(equirect, dtype=np.float32).tobytes(), dtype="f4")
        eq.repeat_y = False
        prog = build_program(ctx, "fullscreen.vert.glsl", "equirect_to_cube.frag.glsl")
        vao = ctx.vertex_array(prog, [])
        target = ctx.texture((size, 6 * size), 4, dtype="f4")
        fbo = ctx.framebuffer(color_attachments=[target])
        try:
            fbo.use()
            eq.use(0)
            prog["u_equirect"] = 0
            prog["u_size"] = size
            vao.render(mode=ctx.TRIANGLES, vertices=3)
            cube = np.frombuffer(fbo.read(components=4, dtype="f4"), np.float32).reshape(6, size, size, 4)
        finally:
            for obj in (fbo, target, vao, prog, eq):
                obj.release()
        self = cls(np.ascontiguousarray(cube[..., :3]), ctx)
        self._own_ctx = own
        return self

    def _upload(self, src_cube: np.ndarray) -> None:
        self.tex = self.ctx.texture_cube(
            (self.src_size, self.src_size),
            3,
            np.ascontiguousarray(src_cube, dtype=np.float32).tobytes(),
            dtype="f4",
        )
        self.tex.build_mipmaps()
        self.max_lod = float(math.log2(self.src_size))

    def run(self, exponent: float, out_size: int, grid: int) -> np.ndarray:
        """Prefiltered cube (6, out, out, 3) float32 for one exponent (grid × grid quadrature)."""
        umax, lod = grid_parameters(exponent, grid, self.src_size)
        target = self.ctx.texture((out_size, 6 * out_size), 4, dtype="f4")
        fbo = self.ctx.framebuffer(color_attachments=[target])
        try:
            fbo.use()
            self.tex.use(0)
            self.prog["u_src"] = 0
            self.prog["u_exponent"] = float(exponent)
            self.prog["u_grid"] = int(grid)
            self.prog["u_size"] = int(out_size)
            self.prog["u_umax"] = umax
            self.prog["u_lod"] = min(lod, self.max_lod)
            self.vao.render(mode=self.ctx.TRIANGLES, vertices=3)
            data = np.frombuffer(fbo.read(components=4, dtype="f4"), dtype=np.float32)
        finally:
            fbo.release()
            target.release()
        return data.reshape(6, out_size, out_size, 4)[..., :3].copy()

    def release(self) -> None:
        """Free the GL objects (and the context if this object created it)."""
        for obj in (self.vao, self.prog, self.tex):
            obj.release()
        if self._own_ctx:
            self.ctx.release()

    def __enter__(self) -> GLPrefilter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


@dataclass(frozen=True, eq=False)
class PrefilteredBasis:
    """Everything the renderers read for one environment and lobe basis."""

    env_name: str
    env_hash: str
    exponents: tuple[float, ...]
    cubes: tuple[np.ndarray, ...] = field(repr=False)  # one (6, S_i, S_i, 3) float32 per exponent
    sh: np.ndarray = field(repr=False)  # (9, 3) radiance SH coefficients
    diffuse: np.ndarray = field(repr=False)  # (6, 16, 16, 3) exponent-1 map = E/π
    engine: str = "gl"
    timings: dict[str, float] = field(default_factory=dict)
    lights: Lights | None = None  # taken out of the wide lobes' maps
    wide: tuple[bool, ...] = ()  # lobe i prefiltered from the residual map
    diffuse_source: np.ndarray | None = field(default=None, repr=False)  # the coat map's source cube
    coat_maps: dict[float, np.ndarray] = field(default_factory=dict, repr=False)  # coat index → D_coat
    light_maps: dict[tuple[int, int], np.ndarray] = field(default_factory=dict, repr=False)  # light_maps.py
    cache: PrefilterCache | None = field(default=None, repr=False)  # where coat maps are kept on disk


def coat_diffuse_map(basis: PrefilteredBasis, coat: ClearCoat, ctx: Any = None) -> np.ndarray:
    """The coat-transmitted diffuse map D_coat (6, COAT_DIFFUSE_SIZE, COAT_DIFFUSE_SIZE, 3) float32 of
    *basis* for *coat* (module docstring), summed on first use from the basis's source cube and kept on
    the basis: on the GL context *ctx* (:class:`GLBrute`) when given, else by :func:`prefilter_brute`
    (the same terms). With the basis's disk cache (:attr:`PrefilteredBasis.cache`) the map is read from,
    or stored in, the cache (float32, keyed by the environment's content hash, the coat's index, the
    sizes and the engine: :meth:`PrefilterCache.coat_key`), so it is summed once per environment and
    coat, not once per basis; a cached map equals the summed one exactly. A basis made without a coat
    pays nothing for it. Units: radiance."""
    if coat.index not in basis.coat_maps:
        src = basis.diffuse_source
        if src is None:
            raise RenderError("prefilter: this basis has no source cube for a coat map")
        shape = (6, COAT_DIFFUSE_SIZE, COAT_DIFFUSE_SIZE, 3)
        key = PrefilterCache.coat_key(
            basis.env_hash, coat.index, COAT_DIFFUSE_SIZE, src.shape[1], "numpy" if ctx is None else "gl"
        )
        cube = basis.cache.get(key, shape) if basis.cache is not None else None
        if cube is None:
            if ctx is not None:
                with GLBrute(ctx) as gl:
                    cube = gl.run(src, 1.0, COAT_DIFFUSE_SIZE, coat)
            else:
                cube = prefilter_brute(src, 1.0, COAT_DIFFUSE_SIZE, coat).astype(np.float32)
            if basis.cache is not None:
                basis.cache.put(key, cube, np.float32)
        basis.coat_maps[coat.index] = cube
    return basis.coat_maps[coat.index]


def _sample_lobes(
    engine: str,
    sources: tuple[Environment, Environment],
    src: int,
    plan: Sequence[tuple[float, int, int]],
    wide: Sequence[bool],
    sampled: Sequence[int],
    cubes: list[np.ndarray | None],
    gl_ctx,
) -> None:
    """Prefilter the lobes *sampled* (indices into *plan*) by the tangent-grid quadrature into *cubes*,
    grouped by source (``sources[int(wide[i])]``: the full map, or the residual without its lights)."""
    for k in (0, 1):
        group = [i for i in sampled if int(wide[i]) == k]
        if not group:
            continue
        source = sources[k]
        if engine == "gl":
            with GLPrefilter.from_equirect(source.equirect, src, gl_ctx) as gl:
                for i in group:
                    cubes[i] = gl.run(*plan[i])
        else:
            src_cube = source.to_cube(src)
            for i in group:
                cubes[i] = prefilter_grid_numpy(src_cube, *plan[i]).astype(np.float32)


def compute_maps(
    env: Environment,
    residual: Environment,
    src: int,
    plan: Sequence[tuple[float, int, int]],
    wide: Sequence[bool],
    todo: Sequence[int],
    cubes: list[np.ndarray | None],
    engine: str,
    ctx,
    timings: dict[str, float],
    diffuse: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Compute the lobe maps *todo* into *cubes* (brute-force sums up to BRUTE_MAX_SIZE, the quadrature
    above) and return the diffuse map (*diffuse* when given: the cached one; else summed) and the coat
    map's source cube (:func:`coat_diffuse_map`); seconds per stage into *timings*. A GL context is made
    (and released) when *engine* is ``gl``, *ctx* is None and a map is to be computed."""
    small: dict[tuple[int, int], np.ndarray] = {}

    def small_cube(k: int, size: int) -> np.ndarray:
        if (k, size) not in small:
            small[(k, size)] = cubemap.equirect_to_cube((residual if k else env).equirect, size)
        return small[(k, size)]

    work = engine == "gl" and (bool(todo) or diffuse is None)
    own = work and ctx is None
    gl_ctx = create_gl_context() if own else ctx
    brute_gl = GLBrute(gl_ctx) if work else None

    def brute(k: int, exponent: float, size: int, src_size: int) -> np.ndarray:
        cube = small_cube(k, src_size)
        if brute_gl is not None:
            return brute_gl.run(cube, exponent, size)
        return prefilter_brute(cube, exponent, size).astype(np.float32)

    try:
        if todo:
            t0 = time.perf_counter()
            for i in [i for i in todo if plan[i][1] <= BRUTE_MAX_SIZE]:
                e, size, _ = plan[i]
                cubes[i] = brute(int(wide[i]), e, size, max(32, 2 * size))
            timings["brute"] = time.perf_counter() - t0
            t0 = time.perf_counter()
            sampled = [i for i in todo if plan[i][1] > BRUTE_MAX_SIZE]
            _sample_lobes(engine, (env, residual), src, plan, wide, sampled, cubes, gl_ctx)
            timings["lobes"] = time.perf_counter() - t0
        if diffuse is None:
            t0 = time.perf_counter()
            diffuse = brute(0, 1.0, DIFFUSE_SIZE, DIFFUSE_SOURCE_SIZE)
            timings["diffuse"] = time.perf_counter() - t0
    finally:
        if brute_gl is not None:
            brute_gl.release()
        if own:
            gl_ctx.release()
    return diffuse, small_cube(0, COAT_SOURCE_SIZE)


def prefilter_basis(
    env: Environment,
    exponents: Sequence[float],
    *,
    engine: str = "auto",
    cache: PrefilterCache | None = None,
    ctx=None,
    max_size: int | None = None,
    lights: bool = True,
) -> PrefilteredBasis:
    """Prefilter *env* for every exponent, plus its SH coefficients (timings in seconds).

    engine: ``gl`` (the tangent-grid quadrature, and the brute-force sums of the wide lobes and the
    diffuse map (:class:`GLBrute`), on the GL context), ``numpy`` (same estimators, slower; output faces
    capped at 64) or ``auto`` (GL when a context can be made). *cache* (optional) stores and reuses
    maps on disk. *max_size* caps the output face size (level of detail). With *lights* (default)
    compact bright sources are taken out of the environment (:func:`extract_lights`): lobes with
    E < WIDE_EXPONENT are prefiltered from the residual and the renderers shade the lights exactly
    for them; narrow lobes and the diffuse map keep the full environment.
    """
    exps = tuple(check_exponent(e) for e in exponents)
    if engine not in ("auto", "gl", "numpy"):
        raise RenderInputError("engine", "auto | gl | numpy", engine)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    coeffs = sh_project(env.downsampled(256).equirect)
    timings["sh"] = time.perf_counter() - t0
    src = source_size(env)
    if engine == "auto":
        engine = "gl" if ctx is not None or gl_available() else "numpy"
    cap = max_size or (src if engine == "gl" else min(src, 64))
    plan = []
    for e in exps:
        size = min(output_size(e, src), cap)
        plan.append((e, size, sample_count(size)))
    residual, found = extract_lights(env) if lights else (env, None)
    wide = tuple(bool(found is not None and found.count and e < WIDE_EXPONENT) for e in exps)
    sources = [residual if w else env for w in wide]
    keys = [
        PrefilterCache.key(sources[i].content_hash, e, s, src, n, engine) for i, (e, s, n) in enumerate(plan)
    ]
    cubes: list[np.ndarray | None] = [cache.get(k) if cache else None for k in keys]
    todo = [i for i, c in enumerate(cubes) if c is None]
    # the diffuse map depends on the environment alone: cached exactly (float32) like the coat's map
    dkey = PrefilterCache.diffuse_key(env.content_hash, DIFFUSE_SIZE, DIFFUSE_SOURCE_SIZE, engine)
    cached = cache.get(dkey, (6, DIFFUSE_SIZE, DIFFUSE_SIZE, 3)) if cache else None
    diffuse, coat_src = compute_maps(
        env, residual, src, plan, wide, todo, cubes, engine, ctx, timings, cached
    )
    if cache and cached is None:
        cache.put(dkey, diffuse, np.float32)
    maps = [c for c in cubes if c is not None]
    if len(maps) != len(cubes):
        raise RenderError("prefilter: a lobe was neither cached nor computed")
    if todo and cache:
        for i in todo:
            cache.put(keys[i], maps[i])
            # as the cache stores it (float16), so a first render equals every later one
            maps[i] = maps[i].astype(np.float16).astype(np.float32)
    timings["cache_hits"] = float(len(exps) - len(todo))
    return PrefilteredBasis(
        env_name=env.name,
        env_hash=env.content_hash,
        exponents=exps,
        cubes=tuple(maps),
        sh=coeffs,
        diffuse=diffuse,
        engine=engine,
        timings=timings,
        lights=found if any(wide) else None,
        wide=wide,
        diffuse_source=coat_src,
        cache=cache,
    )
