"""Ground truth: the designed BRDF itself integrated against an environment, per pixel (issue 3).

For a pixel with unit normal N and unit view direction V (surface → eye), the reflected radiance is

    L_o = ∫ L_env(ω) · f(ω, V)(N·ω) dω
        = ∫ L_env(ω) [ (N·ω)₊ ρ(ψ)/π + 1[N·ω > 0] ρ_s (n+1)/(2π) cosⁿψ ] dω,     cos ψ = ω·R_V,

R_V = 2(N·V)N − V (the aspecular angle of light ω seen from V is ψ, by the symmetry of the mirror),
with the designed BRDF of :mod:`station.render.lobe_fit` (clamped-quadratic colour, Phong gloss):
no lobe approximation. The same integrator evaluates the lobe model (eqs 2.3.1–2.3.3), exactly or as
the prefiltered renderer does (eqs 2.5.1–2.5.3: DD weighted by (R·N), lobes not clipped at the
horizon), so differences measure the approximation and not the integration.

Integration (units: radiance in the environment's units, linear sRGB):

* bright compact sources (pixels brighter than POINT_THRESHOLD × the mean luminance, e.g. a sun disc)
  are taken out of the map as point lights (direction, radiance × solid angle), evaluated exactly;
* kernels that are broad in ψ (the colour term; lobes with exponent < SHARP_EXPONENT) use the rest of
  the map box-filtered to a quadrature of QUADRATURE_WIDTH × QUADRATURE_WIDTH/2 directions;
* sharp lobes (exponent ≥ SHARP_EXPONENT) are importance sampled about R_V with a fixed stratified set
  of LOBE_SAMPLES directions from the pdf (E+1)/(2π) cos^E ψ, looking up the full-resolution map
  bilinearly.

Per pixel the quadrature and point lights are first binned by ψ on the 0.25° grid of the designed
BRDF's table (linear hat weights, the same interpolation :meth:`DesignedBRDF.rho` uses), so each further
design or lobe costs one dot product per pixel.

Clear coat: with a :class:`station.model.gloss.ClearCoat` the gloss term (the designed BRDF's Phong
lobe, the lobe model's K_G lobes) is multiplied per pixel by s(N·V) = F(N·V)/ρ_ref (the coat's exact
dielectric Fresnel) and the colour terms by 1 − F(N·V), the factors the renderers apply; ``coat=None``
is the thesis's BRDF. The diffuse base also sees each incoming direction through the coat: per sample
(quadrature direction or point light) its weight (N·ω)₊ is multiplied by t(N·ω) = (1 − F(N·ω))/(1 −
F_dr,ext) (``ClearCoat.entry_scale``, Mitsuba's ``plastic``; a uniform environment is unchanged). The
diffuse base is K_D of the lobe model and, of a designed BRDF, its colour floor ρ_d = min_ψ ρ(ψ) (per
channel, ≥ 0: the flop colour the clamped quadratic reaches at its travel); the effect part ρ(ψ) − ρ_d,
like the K_DD lobes and the fall-off, keeps the outgoing factor alone (``ClearCoat``'s docstring).

Shadows (optional, ``visibility`` / :func:`render_truth`'s *positions* and *scene*): each point light (the
sun) counts at a pixel times its visibility there, decided by a ray from the pixel's point at the shape
itself (``station.render.shapes.ray_cast_visibility``, no sphere proxies), in every term but the
near-mirror lobes' whole-map samples; the rest of the map (the sky) is not shadowed, as in the renderers.
On a stage turned by θ the normals and views are in the environment's frame (as the renderers' lookups) and
the rays turn back to the world's (``station.render.stage.lookup_matrix``).

Near-mirror lobes: a lobe narrower than MIRROR_PIXELS map pixels (:func:`resolves_pixels`; a 100 GU
design's n = 10⁷) would miss point lights at pixel centres, so it importance-samples the whole map with
the bright pixels left in, as small area lights (the reflection of a sun disc in a mirror is the disc).

Flakes: :func:`station.render.truth_flakes.flake_sparkle_truth` is the flake layer's sparkle with the full-resolution map and the
exact expected flake reflection (the renderers use the sharpest and a matching lobe map).

Environments: anything with an ``equirect`` array (H, 2H, 3) (``station.render.environment.
Environment``) or the array itself, in the equirectangular convention of ``station.render.cubemap``
(+Y up, θ from +Y down the rows, φ = 2π(u − ½), direction (sin θ sin φ, cos θ, −sin θ cos φ)).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.gloss import ClearCoat
from station.render.errors import RenderInputError
from station.render.lobe_fit import ALPHA_GRID_DEG, DesignedBRDF, designed_brdf, fall_off_factor
from station.render.lobes import bent_direction, horizon_factors
from station.render.shapes import Scene, ray_cast_visibility
from station.render.stage import lookup_matrix
from station.render.truth_lighting import MAX_POINT_LIGHTS as MAX_POINT_LIGHTS
from station.render.truth_lighting import MIRROR_PIXELS as MIRROR_PIXELS
from station.render.truth_lighting import PIXEL_CHUNK, tangent_frames
from station.render.truth_lighting import POINT_THRESHOLD as POINT_THRESHOLD
from station.render.truth_lighting import QUADRATURE_WIDTH as QUADRATURE_WIDTH
from station.render.truth_lighting import Lighting as Lighting
from station.render.truth_lighting import equirect_directions as equirect_directions
from station.render.truth_lighting import equirect_solid_angles as equirect_solid_angles
from station.render.truth_lighting import prepare_lighting as prepare_lighting
from station.render.truth_lighting import resolves_pixels as resolves_pixels
from station.render.truth_lighting import sample_equirect as sample_equirect
from station.render.weights import LobeWeights

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

#: Exponent from which a lobe is importance sampled instead of using the quadrature.
SHARP_EXPONENT = 64.0
#: Importance samples per pixel and sharp lobe.
LOBE_SAMPLES = 256
#: N·V given to silhouette pixels by ``render_truth(backfacing="bend")``.
BEND_COS = 1e-3
#: How :meth:`TruthScene.lobes` evaluates the lobe model.
LOBE_MODES = ("exact", "prefiltered", "prefiltered-lut", "prefiltered-lut+lights", "prefiltered-bent+lights")
_BINS = ALPHA_GRID_DEG.size  # 721 bins of 0.25°
_COS_GRID = np.cos(np.radians(ALPHA_GRID_DEG))


def _lobe_samples(exponent: float, count: int) -> NDArray[np.float64]:
    """Stratified directions about +z with pdf (E+1)/(2π) cos^E ψ (golden-angle spiral), (count, 3)."""
    u = (np.arange(count) + 0.5) / count
    cos_psi = u ** (1.0 / (exponent + 1.0))
    sin_psi = np.sqrt(np.maximum(0.0, 1.0 - cos_psi**2))
    phi = np.arange(count) * np.pi * (3.0 - np.sqrt(5.0))
    return np.stack([sin_psi * np.cos(phi), sin_psi * np.sin(phi), cos_psi], axis=-1)


def diffuse_floor(brdf: DesignedBRDF) -> NDArray[np.float64]:
    """ρ_d (3,): the designed BRDF's colour floor min_ψ ρ(ψ) per channel, ≥ 0, the share of its colour the
    clear coat treats as the diffuse base (module docstring; the flop colour of a clamped quadratic)."""
    return np.asarray(np.maximum(brdf.reflectance.min(axis=0), 0.0), dtype=float)


class TruthScene:
    """Per-pixel integrals of one environment for a set of normals and views (reused across designs).

    Parameters
    ----------
    environment
        Equirect map or an object with ``equirect`` (module docstring).
    normals, views
        (..., 3) unit normals N and unit directions to the eye V, same shape; N·V must be > 0.
    samples
        Importance samples per pixel and sharp lobe.
    quadrature_width
        Width of the quadrature map for broad kernels.
    visibility
        Shadows: a function of the point lights' directions (k, 3) giving each pixel's visibility of each,
        (P, k) in [0, 1] (:func:`render_truth`'s ray cast); None: every point light visible.
    """

    def __init__(
        self,
        environment: Any,
        normals: ArrayLike,
        views: ArrayLike,
        samples: int = LOBE_SAMPLES,
        quadrature_width: int = QUADRATURE_WIDTH,
        lighting: Lighting | None = None,
        visibility: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None,
    ) -> None:
        n = np.asarray(normals, dtype=float)
        v = np.asarray(views, dtype=float)
        if n.shape != v.shape or n.shape[-1:] != (3,):
            raise RenderInputError(
                "normals/views", "two arrays of unit vectors (..., 3) of one shape", (n.shape, v.shape)
            )
        if not (np.all(np.isfinite(n)) and np.all(np.isfinite(v))):
            raise RenderInputError("normals/views", "finite unit vectors", "non-finite values")
        if samples < 16:
            raise RenderInputError("samples", "at least 16 importance samples", samples)
        self.shape = n.shape[:-1]
        n = n.reshape(-1, 3) / np.linalg.norm(n.reshape(-1, 3), axis=1, keepdims=True)
        v = v.reshape(-1, 3) / np.linalg.norm(v.reshape(-1, 3), axis=1, keepdims=True)
        n_dot_v = np.einsum("ij,ij->i", n, v)
        if np.any(n_dot_v <= 0.0):
            raise RenderInputError("views", "directions on the normal's side (N·V > 0)", "back-facing pixels")
        self.normals, self.views = n, v
        self.reflect = 2.0 * n_dot_v[:, None] * n - v
        self.samples = int(samples)
        self.lighting = prepare_lighting(environment, quadrature_width) if lighting is None else lighting
        self.point_vis = None if visibility is None else visibility(self.lighting.point_dirs)  # (P, k)
        self._bent: dict[float, NDArray[np.float64]] = {}
        self._tangents = tangent_frames(self.reflect)
        self._cache: dict[tuple[str, float], NDArray[np.float64]] = {}  # lobe integrals, coat irradiance
        self._horizon: dict[float, tuple[NDArray[np.float64], NDArray[np.float64]]] = {}
        self._hist: dict[str, NDArray[np.float64]] = {}

    # -- binned broad kernels -------------------------------------------------------------------------

    def _hist_of(self, prefix: str, kind: str) -> NDArray[np.float64]:
        """Per pixel, flux binned by ψ (P, 721, 3) for the quadrature ("q") or point lights ("p"),
        weighted by (N·ω)₊ ("cos"), 1[N·ω>0] ("mask") or 1 ("open"); built on first use."""
        key = f"{prefix}_{kind}"
        if key in self._hist:
            return self._hist[key]
        dirs, flux = (
            (self.lighting.quad_dirs, self.lighting.quad_flux)
            if prefix == "q"
            else (self.lighting.point_dirs, self.lighting.point_flux)
        )
        px = self.normals.shape[0]
        hist = np.zeros((px, _BINS, 3))
        if dirs.shape[0]:
            for s in range(0, px, PIXEL_CHUNK):
                sl = slice(s, min(px, s + PIXEL_CHUNK))
                cos_psi = np.clip(self.reflect[sl] @ dirs.T, -1.0, 1.0)
                n_dot = self.normals[sl] @ dirs.T
                a = np.degrees(np.arccos(cos_psi)) * 4.0
                i0 = np.minimum(a.astype(np.int64), _BINS - 2)
                t = (a - i0)[..., None]
                wgt = {"cos": np.maximum(n_dot, 0.0), "mask": (n_dot > 0.0) * 1.0, "open": None}[kind]
                if prefix == "p" and self.point_vis is not None:  # the point lights' shadows
                    wgt = self.point_vis[sl] if wgt is None else wgt * self.point_vis[sl]
                f = flux[None, :, :] if wgt is None else wgt[..., None] * flux[None, :, :]
                idx = (np.arange(sl.stop - sl.start)[:, None] * _BINS + i0)[..., None] * 3 + np.arange(3)
                size = (sl.stop - sl.start) * _BINS * 3
                acc = np.bincount(idx.ravel(), np.broadcast_to(f * (1 - t), idx.shape).ravel(), size)
                acc += np.bincount((idx + 3).ravel(), np.broadcast_to(f * t, idx.shape).ravel(), size)
                hist[sl] = acc.reshape(-1, _BINS, 3)
        self._hist[key] = hist
        return hist

    def _binned(self, kind: str, kernel: NDArray[np.float64], points_only: bool) -> NDArray[np.float64]:
        """Σ_bins hist · kernel(ψ_bin), (P, 3); kernel (721,) or (721, 3)."""
        k = kernel if kernel.ndim == 2 else kernel[:, None]
        total = np.einsum("pbc,bc->pc", self._hist_of("p", kind), np.broadcast_to(k, (_BINS, 3)))
        if not points_only:
            total = total + np.einsum("pbc,bc->pc", self._hist_of("q", kind), np.broadcast_to(k, (_BINS, 3)))
        return total

    # -- lobe integrals ------------------------------------------------------------------------------

    def lobe(self, exponent: float, kind: str) -> NDArray[np.float64]:
        """∫ L(ω) cos^E ψ · w(ω) dω per pixel, (P, 3); w = (N·ω)₊ ("cos"), 1[N·ω>0] ("mask"), 1 ("open")."""
        key = (kind, float(exponent))
        if key in self._cache:
            return self._cache[key]
        cos_grid = np.cos(np.radians(ALPHA_GRID_DEG))
        kernel = np.clip(cos_grid, 0.0, 1.0) ** exponent
        if exponent < SHARP_EXPONENT:
            value = self._binned(kind, kernel, points_only=False)
        elif self._area_lights(exponent):
            value = self._sampled(exponent, kind, self.lighting.full)
        else:
            value = self._binned(kind, kernel, points_only=True) + self._sampled(exponent, kind)
        self._cache[key] = value
        return value

    def _area_lights(self, exponent: float) -> bool:
        """Whether a sharp lobe samples the whole map, point lights as pixels (:func:`resolves_pixels`)."""
        return exponent >= SHARP_EXPONENT and resolves_pixels(exponent, self.lighting.full.shape[0])

    def _sampled(
        self, exponent: float, kind: str, image: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """Importance-sampled ∫ L cos^E ψ w dω over *image* (default: the residual map), (P, 3)."""
        image = self.lighting.residual if image is None else image
        local = _lobe_samples(exponent, self.samples)
        t, b = self._tangents
        out = np.empty((self.normals.shape[0], 3))
        for s in range(0, out.shape[0], PIXEL_CHUNK):
            sl = slice(s, min(out.shape[0], s + PIXEL_CHUNK))
            dirs = (
                local[None, :, 0:1] * t[sl, None, :]
                + local[None, :, 1:2] * b[sl, None, :]
                + local[None, :, 2:3] * self.reflect[sl, None, :]
            )
            rad = sample_equirect(image, dirs)
            n_dot = np.einsum("pkc,pc->pk", dirs, self.normals[sl])
            w = {"cos": np.maximum(n_dot, 0.0), "mask": (n_dot > 0.0) * 1.0, "open": np.ones_like(n_dot)}[
                kind
            ]
            out[sl] = (rad * w[..., None]).mean(axis=1) * (2.0 * np.pi / (exponent + 1.0))
        return out

    def irradiance(self) -> NDArray[np.float64]:
        """E(N) = ∫ L (N·ω)₊ dω per pixel, (P, 3)."""
        return self.lobe(0.0, "cos")

    # -- shading -------------------------------------------------------------------------------------

    def _seen(self, sl: slice) -> NDArray[np.float64] | float:
        """Visibility (p, M) of the quadrature directions (1: the sky is not shadowed) and point lights; 1.0
        without shadows."""
        if self.point_vis is None:
            return 1.0
        vis = self.point_vis[sl]
        return np.concatenate([np.ones((vis.shape[0], self.lighting.quad_dirs.shape[0])), vis], axis=1)

    def coat_factors(self, coat: ClearCoat | None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Per pixel factors (P, 1) on the gloss and on the base terms: s(N·V) and 1 − F(N·V) of *coat*,
        ones for None (module docstring)."""
        if coat is None:
            one = np.ones((self.normals.shape[0], 1))
            return one, one
        n_dot_v = np.einsum("ij,ij->i", self.normals, self.views)
        return coat.gloss_scale(n_dot_v)[:, None], coat.base_scale(n_dot_v)[:, None]

    def coat_irradiance(self, coat: ClearCoat) -> NDArray[np.float64]:
        """E_coat(N) = ∫ L(ω) t(N·ω) (N·ω)₊ dω per pixel, (P, 3): the irradiance the diffuse base receives
        through *coat* (t = ``coat.entry_scale``; module docstring), summed over the quadrature directions
        and the point lights (the sampled lobes' maps are the same light)."""
        key = ("coat", coat.index)
        if key not in self._cache:
            dirs = np.concatenate([self.lighting.quad_dirs, self.lighting.point_dirs])
            flux = np.concatenate([self.lighting.quad_flux, self.lighting.point_flux])
            out = np.empty((self.normals.shape[0], 3))
            for s in range(0, out.shape[0], PIXEL_CHUNK):
                sl = slice(s, min(out.shape[0], s + PIXEL_CHUNK))
                n_dot = np.maximum(self.normals[sl] @ dirs.T, 0.0)
                out[sl] = (n_dot * coat.entry_scale(n_dot) * self._seen(sl)) @ flux
            self._cache[key] = out
        return self._cache[key]

    def truth(self, brdf: DesignedBRDF, coat: ClearCoat | None = None) -> NDArray[np.float64]:
        """Radiance of the designed BRDF, (..., 3) (module docstring); *coat*: clear-coat Fresnel or None."""
        if coat is None:
            colour = self._binned("cos", brdf.reflectance / np.pi, points_only=False)
        else:  # the colour floor through the coat, the effect part as without it
            floor = diffuse_floor(brdf)
            colour = self._binned("cos", (brdf.reflectance - floor) / np.pi, points_only=False)
            colour = colour + floor[None, :] / np.pi * self.coat_irradiance(coat)
        gloss = (
            brdf.specular_albedo
            * (brdf.phong_exponent + 1.0)
            / (2.0 * np.pi)
            * self.lobe(brdf.phong_exponent, "mask")
        )
        scale, base = self.coat_factors(coat)
        return (base * colour + scale * gloss).reshape(*self.shape, 3)

    def truth_direct(self, brdf: DesignedBRDF, coat: ClearCoat | None = None) -> NDArray[np.float64]:
        """:meth:`truth` without the per-pixel histograms: one pass over the directions for one design.

        Same integrals (up to the 0.25° binning the histograms add); faster when only one design is shaded.
        """
        dirs = np.concatenate([self.lighting.quad_dirs, self.lighting.point_dirs])
        flux = np.concatenate([self.lighting.quad_flux, self.lighting.point_flux])
        n_exp = brdf.phong_exponent
        peak = brdf.specular_albedo * (n_exp + 1.0) / (2.0 * np.pi)
        sharp = n_exp >= SHARP_EXPONENT
        area = self._area_lights(n_exp)
        scale, base = self.coat_factors(coat)
        floor = diffuse_floor(brdf)
        out = np.empty((self.normals.shape[0], 3))
        for s in range(0, out.shape[0], PIXEL_CHUNK):
            sl = slice(s, min(out.shape[0], s + PIXEL_CHUNK))
            cos_psi = np.clip(self.reflect[sl] @ dirs.T, -1.0, 1.0)
            n_dot = self.normals[sl] @ dirs.T
            seen = self._seen(sl)  # the point lights' shadows
            rho = brdf.rho(np.degrees(np.arccos(cos_psi)))
            if coat is not None:  # the colour floor through the coat (module docstring)
                rho = rho + (coat.entry_scale(n_dot) - 1.0)[..., None] * floor
            colour = np.einsum("pm,pmc,mc->pc", np.maximum(n_dot, 0.0) * seen, rho, flux) / np.pi
            lobe = (n_dot > 0.0) * seen * np.clip(cos_psi, 0.0, 1.0) ** n_exp
            if sharp:  # residual map by importance sampling below; only the point lights here
                lobe[:, : self.lighting.quad_dirs.shape[0] if not area else None] = 0.0
            out[sl] = base[sl] * colour + scale[sl] * peak * (lobe @ flux)
        if sharp:
            image = self.lighting.full if area else None
            out += scale * peak * self._sampled(n_exp, "mask", image)
        return out.reshape(*self.shape, 3)

    def lobes(
        self, weights: LobeWeights, mode: str = "exact", coat: ClearCoat | None = None
    ) -> NDArray[np.float64]:
        """Radiance of the lobe model, (..., 3).

        ``exact``: eqs 2.3.1–2.3.3 integrated like the truth. ``prefiltered``: as the renderers evaluate
        it (eqs 2.5.1–2.5.3): K_D E(N) + (R·N)₊ Σ K_DD,i I_i + Σ K_G,i I_i with I_i the unclipped lobe
        integral about R (what a normalised prefiltered map times 2π/(E+1) holds). ``prefiltered-lut``:
        the same lookups with (R·N) replaced by g(E_i, R·N) and the gloss weighted by h(E_i, R·N) from
        :func:`station.render.lobes.horizon_factors` (a small per-lobe table a shader can hold).
        ``prefiltered-lut+lights``: as ``prefiltered-lut`` for the map without its extracted point lights
        (the sun), which are shaded exactly as directional lights. ``prefiltered-bent+lights``: as that,
        with the directionally diffuse lookup of each wide lobe (E < SHARP_EXPONENT) at
        :func:`station.render.lobes.bent_direction` instead of R. *coat*: the clear coat's Fresnel factor
        on every K_G term (module docstring), None for none. The aspecular fall-off term
        K_A ∫ L(ω)(N·ω)₊ min(1, 1 + cos ψ) dω (:mod:`station.render.weights`) is integrated exactly in
        every mode (binned like the truth's colour term).
        """
        if mode not in LOBE_MODES:
            raise RenderInputError("mode", " | ".join(LOBE_MODES), mode)
        # K_D through the coat (module docstring): every mode, as the renderers' coat-transmitted map
        base = weights.k_d[None, :] * (self.irradiance() if coat is None else self.coat_irradiance(coat))
        if weights.has_fall_off:
            base = base + weights.k_a[None, :] * self._binned(
                "cos", fall_off_factor(_COS_GRID), points_only=False
            )
        gloss = np.zeros_like(base)
        r_dot_n = np.einsum("ij,ij->i", self.reflect, self.normals)
        for i, e in enumerate(weights.exponents):
            if mode == "exact":
                base = base + weights.k_dd[i][None, :] * self.lobe(e, "cos")
                gloss = gloss + weights.k_g[i] * self.lobe(e, "mask")
                continue
            lobe = self.lobe(e, "open")
            if mode == "prefiltered":
                g, h = np.maximum(r_dot_n, 0.0), np.ones_like(r_dot_n)
            else:
                if e not in self._horizon:
                    self._horizon[e] = horizon_factors(e, r_dot_n)
                g, h = self._horizon[e]
            dd_lobe = lobe
            if mode in ("prefiltered-lut+lights", "prefiltered-bent+lights"):
                # Point lights shaded exactly (as a renderer shades a few directional lights), the rest of
                # the map through the prefiltered lookups.
                kernel = np.clip(np.cos(np.radians(ALPHA_GRID_DEG)), 0.0, 1.0) ** e
                lobe = lobe - self._binned("open", kernel, points_only=True)
                dd_lobe = (
                    self._bent_lobe(e) if mode == "prefiltered-bent+lights" and e < SHARP_EXPONENT else lobe
                )
                base = base + weights.k_dd[i][None, :] * self._binned("cos", kernel, points_only=True)
                gloss = gloss + weights.k_g[i] * self._binned("mask", kernel, points_only=True)
            base = base + weights.k_dd[i][None, :] * g[:, None] * dd_lobe
            gloss = gloss + weights.k_g[i] * h[:, None] * lobe
        scale, attenuation = self.coat_factors(coat)
        out = attenuation * base + scale * gloss
        return out.reshape(*self.shape, 3)

    def _bent_lobe(self, exponent: float) -> NDArray[np.float64]:
        """Open lobe integral of the map without point lights about B = bent_direction(E, R, N), (P, 3)."""
        if exponent not in self._bent:
            b = bent_direction(exponent, self.reflect, self.normals)
            views = 2.0 * np.einsum("ij,ij->i", self.normals, b)[:, None] * self.normals - b  # mirror of B
            aux = TruthScene(
                self.lighting.residual, self.normals, views, self.samples, lighting=self.lighting
            )
            kernel = np.clip(np.cos(np.radians(ALPHA_GRID_DEG)), 0.0, 1.0) ** exponent
            self._bent[exponent] = aux.lobe(exponent, "open") - aux._binned("open", kernel, points_only=True)
        return self._bent[exponent]

    def white(self) -> NDArray[np.float64]:
        """Radiance of a white Lambertian surface (reflectance 1) at each pixel, (..., 3)."""
        return (self.irradiance() / np.pi).reshape(*self.shape, 3)


def bend_silhouettes(normals: ArrayLike, views: ArrayLike) -> tuple[NDArray[np.float64], int]:
    """Silhouette fix: normals with N·V <= BEND_COS turned towards the view until N·V = BEND_COS.

    *normals* and *views* are (..., 3) (views: unit directions from the surface to the eye). Returns the
    corrected normals (a copy) and how many were turned; arrays of other shapes come back unchanged.
    """
    n = np.array(normals, dtype=float)
    v = np.asarray(views, dtype=float)
    if n.shape != v.shape or n.shape[-1:] != (3,):
        return n, 0
    vn = v / np.linalg.norm(v, axis=-1, keepdims=True)
    n_dot_v = np.einsum("...i,...i->...", n, vn) / np.linalg.norm(n, axis=-1)
    low = n_dot_v <= BEND_COS
    bent = int(low.sum())
    if bent:
        nl = n[low] / np.linalg.norm(n[low], axis=-1, keepdims=True)
        tangent = nl - n_dot_v[low][:, None] * vn[low]
        norm_t = np.linalg.norm(tangent, axis=-1, keepdims=True)
        tangent = np.where(norm_t > 1e-12, tangent / np.where(norm_t > 1e-12, norm_t, 1.0), 0.0)
        n[low] = BEND_COS * vn[low] + np.sqrt(1.0 - BEND_COS**2) * tangent
    return n, bent


def _world_visibility(
    scene: Scene,
    points: NDArray[np.float64],
    normals: NDArray[np.float64],
    turn: NDArray[np.float64],
    directions: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Visibility (P, k) of lights at *directions* (k, 3) in the environment's frame, for world *points* and
    *normals* (P, 3): the ray cast with the directions turned to the world's (w = Mᵀe, *turn* = M)."""
    return ray_cast_visibility(scene, points, normals, np.asarray(directions, dtype=float) @ turn)


def render_truth(
    design: FaceFlopTravelGloss | DesignedBRDF,
    environment: Any,
    normals: ArrayLike,
    views: ArrayLike,
    *,
    samples: int = LOBE_SAMPLES,
    quadrature_width: int = 64,
    backfacing: str = "bend",
    coat: ClearCoat | None = None,
    positions: ArrayLike | None = None,
    scene: Scene | None = None,
) -> NDArray[np.float64]:
    """Ground-truth radiance of *design* in *environment* per pixel (for ``station render --engine truth``).

    Parameters
    ----------
    design
        A FaceFlopTravelGloss design (or an already tabulated DesignedBRDF).
    environment
        ``station.render.environment.Environment`` or an equirect array (H, 2H, 3), linear sRGB radiance.
    normals, views
        (..., 3) unit surface normals and unit directions from the surface to the eye (world space, the
        environment's frame).
    samples, quadrature_width
        Accuracy controls (module docstring). The quadrature of 64 × 32 directions for broad kernels
        stays within CIEDE2000 0.07 (95th percentile; 0.29 max) of 256 × 128 on the procedural booth
        and sky and is 20× faster; ``bench.basis_accuracy`` uses 256.
    backfacing
        Pixels with N·V <= BEND_COS (silhouettes of shading normals): ``"bend"`` turns the normal towards
        the view until N·V = BEND_COS (the usual silhouette fix, :func:`bend_silhouettes`); ``"error"``
        refuses them.
    coat
        Clear-coat Fresnel on the gloss lobe (:class:`station.model.gloss.ClearCoat`); None: the thesis's
        BRDF without it.
    positions, scene
        Shadows (module docstring): the pixels' world points (..., 3) on *scene*'s shape
        (:class:`station.render.shapes.Scene`); each point light is seen where its ray misses the shape
        (:func:`station.render.shapes.ray_cast_visibility`). On a stage turned by θ
        (``scene.stage.rotation_deg``) *normals* and *views* are in the environment's frame, R_y(−θ) of the
        world's (:func:`station.render.stage.lookup_matrix`, as the NumPy renderer's lookups), and the
        rays are cast in the world's. None: no shadows.

    Returns
    -------
    ndarray
        (..., 3) scene-linear sRGB radiance in the environment's units (no tone mapping).
    """
    if backfacing not in ("bend", "error"):
        raise RenderInputError("backfacing", "bend | error", backfacing)
    n = np.array(normals, dtype=float)
    v = np.asarray(views, dtype=float)
    if backfacing == "bend":
        n, _ = bend_silhouettes(n, v)
    brdf = design if isinstance(design, DesignedBRDF) else designed_brdf(design)
    vis: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None
    if positions is not None and scene is not None:
        # normals and light directions from the environment's frame back to the world's: e = M w
        turn = lookup_matrix(scene.stage.rotation_deg if scene.stage is not None else 0.0)
        p, nn = np.asarray(positions, dtype=float).reshape(-1, 3), n.reshape(-1, 3) @ turn
        vis = partial(_world_visibility, scene, p, nn, turn)
    return TruthScene(environment, n, v, samples, quadrature_width, visibility=vis).truth_direct(brdf, coat)


def sphere_pixels(size: int, radius: float = 0.98) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Normals and views of an orthographic sphere seen along −Z (the cubemap default camera), (P, 3) each.

    Pixels whose normal lies within *radius* of the silhouette centre (excluding the grazing rim).
    """
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)
    inside = x**2 + y**2 <= radius**2
    nz = np.sqrt(np.maximum(0.0, 1.0 - x**2 - y**2))
    normals = np.stack([x[inside], y[inside], nz[inside]], axis=-1)
    views = np.broadcast_to(np.array([0.0, 0.0, 1.0]), normals.shape).copy()
    return normals, views
