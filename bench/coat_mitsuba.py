"""The physical clear coat against an independent renderer: Mitsuba 3 (``scalar_rgb``, ``plastic`` and
``roughplastic``) under the same environments.

Run: ``.venv/bin/python -m bench.coat_mitsuba`` (needs ``pip install -e ".[bench]"``: Mitsuba is a
bench-only extra, never a runtime dependency). A unit sphere seen orthographically along −Z
(:data:`SIZE`² pixels, box filter), Mitsuba's ``direct`` integrator (the environment reflected once; a
convex sphere has no inter-reflection), :data:`SPP` stratified samples per pixel, seeds 0 and 1.

Environments: ``furnace`` (uniform radiance 1, the white-furnace test) and every ``.hdr`` of
``../shared/data/hdri`` beside the checkout (skipped when absent), loaded by the product
(:func:`station.render.environment.load_environment`) and box-filtered to :data:`ENV_WIDTH` wide; the
same float32 array goes to both renderers. Orientation: the product's equirect has φ = 2π(u − ½), the
image centre along −Z (:mod:`station.render.cubemap`); Mitsuba's ``envmap`` puts −Z at u = 0, so the
array handed to Mitsuba is rolled by half its width. :func:`orientation_check` verifies it on a test scene
before anything is measured: three coloured blobs seen in a mirror sphere, their centroids in Mitsuba
against the product's own lookup (``Environment.radiance``), the roll against no roll and a mirrored map.

Coats (n = 1.5, the product's :data:`station.model.fresnel.CLEAR_COAT_INDEX`):

* ``black 100 GU``: Mitsuba ``plastic`` (a smooth dielectric over black), product the 100 GU design;
* ``white 100 GU``: ``plastic`` over a Lambert base 0.8 (``nonlinear`` false), product k_d = 0.8/π;
* ``black 90 GU``, ``black 60 GU``: ``roughplastic``, Beckmann distribution, α = the Ward α the product
  assigns to that gloss (:func:`station.model.gloss.lobe_from_gloss` ``.ward_alpha``: Ward's isotropic
  lobe exp(−tan²δ/α²)/(π α² cos⁴δ) is Beckmann's D, so the mapping is the identity on α).

Product: ``numpy_renderer.shade_pixels`` with :class:`station.model.gloss.ClearCoat`, the fitted weights
of the design, the numpy prefilter (faces ≤ 64). Each pixel is the mean of :data:`SUPER`² sub-pixel
samples on a regular grid (the same box Mitsuba integrates; a sample that misses the sphere sees the
environment along −Z, as Mitsuba's camera ray does). ``centre`` is the product shaded once at the pixel
centre (what the bench compared before). Baseline, same run: the coat before it (Schlick's F normalised at
60° onto the design's share, base untouched), supersampled the same way.

Reported: per N·V band (of the pixel centre) the ratio of the band's median luminance, product / Mitsuba
(seed 0), with Mitsuba seed 1 / seed 0 as the noise floor; per image the mean CIEDE2000 over the sphere's
pixels (Lab of radiance / the environment's mean luminance, so a white Lambert sphere reads L* ≈ 100),
with Mitsuba seed 0 against seed 1 as the floor.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bench._report import Case, write_section
from station.model import FaceFlopTravelGloss
from station.model.colorimetry import REC709_LUMINANCE, linear_srgb_to_lab
from station.model.difference import delta_e
from station.model.fresnel import CLEAR_COAT_INDEX
from station.model.gloss import ClearCoat, fresnel_schlick, lobe_from_gloss
from station.render import lobe_fit as lf
from station.render import numpy_renderer as nr
from station.render import prefilter
from station.render.cubemap import equirect_directions, equirect_solid_angles
from station.render.environment import Environment, load_environment
from station.render.weights import LobeWeights

HDRI = Path(__file__).resolve().parents[2] / "shared" / "data" / "hdri"
SIZE = 96
SPP = 64
SUPER = 6
SEEDS = (0, 1)
ENV_WIDTH = 512
BANDS = ((0.9, 1.0), (0.5, 0.6), (0.3, 0.4), (0.1, 0.2), (0.02, 0.05))
VIEW = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Coat:
    """One coated paint: its gloss (GU), the Lambert albedo under the coat and Mitsuba's BSDF type."""

    name: str
    gloss: float
    diffuse: float
    bsdf: str  # "plastic" (smooth) or "roughplastic" (Beckmann, α from the product's gloss)


COATS = (
    Coat("black 100 GU", 100.0, 0.0, "plastic"),
    Coat("white 100 GU", 100.0, 0.8, "plastic"),
    Coat("black 90 GU", 90.0, 0.0, "roughplastic"),
    Coat("black 60 GU", 60.0, 0.0, "roughplastic"),
)


def environments() -> dict[str, Environment]:
    """The furnace and the shared HDRs, :data:`ENV_WIDTH` wide."""
    envs = {"furnace": Environment("furnace", np.ones((ENV_WIDTH // 2, ENV_WIDTH, 3), np.float32))}
    for path in sorted(HDRI.glob("*.hdr")):
        env = load_environment(path).downsampled(ENV_WIDTH)
        envs[path.stem] = env
    return envs


def to_mitsuba(equirect: np.ndarray) -> np.ndarray:
    """The product's equirect in Mitsuba's ``envmap`` layout: −Z moved from the centre column to u = 0."""
    return np.ascontiguousarray(np.roll(equirect, equirect.shape[1] // 2, axis=1), dtype=np.float32)


def _grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Sample positions (x, y) in [−1, 1]², row 0 at +Y, *n* × *n*."""
    c = (np.arange(n) + 0.5) / n * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)
    return x, y


def pixel_geometry() -> tuple[np.ndarray, np.ndarray]:
    """N·V (P,) at the pixel centres on the sphere and the mask (SIZE, SIZE) of those pixels."""
    x, y = _grid(SIZE)
    r2 = x * x + y * y
    mask = r2 < 1.0
    return np.sqrt(1.0 - r2[mask]), mask


def _sphere(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(hit mask, normals, mirrored views, N·V) of orthographic rays through (x, y)."""
    r2 = x * x + y * y
    hit = r2 < 1.0
    n = np.stack([x[hit], y[hit], np.sqrt(1.0 - r2[hit])], axis=-1)
    ndv = n @ VIEW
    return hit, n, 2.0 * ndv[:, None] * n - VIEW, ndv


def mitsuba_image(env: np.ndarray, coat: Coat, seed: int, size: int = SIZE, spp: int = SPP) -> np.ndarray:
    """Mitsuba 3 render (size, size, 3) of the coated sphere in the product-layout equirect *env*."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    bsdf: dict[str, object] = {
        "type": coat.bsdf,
        "int_ior": CLEAR_COAT_INDEX,
        "ext_ior": 1.0,
        "diffuse_reflectance": {"type": "rgb", "value": [coat.diffuse] * 3},
        "nonlinear": False,
    }
    if coat.bsdf == "roughplastic":
        bsdf |= {"distribution": "beckmann", "alpha": lobe_from_gloss(coat.gloss).ward_alpha}
    elif coat.bsdf == "conductor":
        bsdf = {"type": "conductor", "material": "none"}
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "direct", "emitter_samples": 4, "bsdf_samples": 4},
            "sensor": {
                "type": "orthographic",
                "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
                "sampler": {"type": "stratified", "sample_count": spp, "seed": seed},
            },
            "emitter": {"type": "envmap", "bitmap": mi.Bitmap(to_mitsuba(env))},
            "sphere": {"type": "sphere", "bsdf": bsdf},
        }
    )
    return np.asarray(mi.render(scene), dtype=float)[..., :3]


def orientation_check() -> dict[str, float]:
    """Largest centroid offset (px) of three coloured blobs in a mirror sphere, Mitsuba against the
    product's lookup, for the roll :func:`to_mitsuba` applies and for two wrong layouts."""
    h, size = 128, 96
    d = equirect_directions(h, 2 * h)
    env = np.zeros((h, 2 * h, 3), np.float32)
    for ch, c in enumerate(([0.5, 0.3, 0.81], [-0.3, 0.6, 0.74], [0.2, -0.5, 0.85])):
        c = np.asarray(c) / np.linalg.norm(c)
        env[..., ch] = 50.0 * np.exp(-2.0 * (1.0 - d @ c) / 0.06**2)
    x, y = _grid(size)
    hit, _n, refl, _ndv = _sphere(x, y)
    ours = np.zeros((size, size, 3))
    ours[hit] = Environment("blobs", env).radiance(refl)
    yy, xx = np.mgrid[:size, :size]

    def centroids(img: np.ndarray) -> np.ndarray:
        w = img * hit[..., None]
        return np.array(
            [[(w[..., c] * xx).sum(), (w[..., c] * yy).sum()] / w[..., c].sum() for c in range(3)]
        )

    mirror = Coat("mirror", 100.0, 0.0, "conductor")
    ref = centroids(ours)
    # mitsuba_image rolls its input; unrolling first gives the map as Mitsuba would read it unconverted.
    layouts = {
        "rolled (used)": env,
        "not rolled": np.roll(env, -env.shape[1] // 2, axis=1),
        "mirrored": np.roll(env[:, ::-1], -env.shape[1] // 2, axis=1),
    }
    return {
        k: float(np.abs(centroids(mitsuba_image(e, mirror, 0, size, 16)) - ref).max())
        for k, e in layouts.items()
    }


def product_image(basis: prefilter.PrefilteredBasis, env: Environment, coat: Coat) -> tuple[np.ndarray, ...]:
    """(supersampled product, pixel-centre product, supersampled baseline) images (SIZE, SIZE, 3)."""
    design = FaceFlopTravelGloss((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), None, coat.gloss, coat.name)
    w = lf.fit_design(design)
    w = LobeWeights(w.exponents, np.full(3, coat.diffuse / np.pi), w.k_dd, w.k_g)
    base_w = LobeWeights(w.exponents, w.k_d, w.k_dd, np.zeros_like(w.k_g))
    gloss_w = LobeWeights(w.exponents, np.zeros(3), w.k_dd * 0.0, w.k_g)
    background = env.radiance(-VIEW[None, :])[0]
    schlick_ref = float(fresnel_schlick(0.5, CLEAR_COAT_INDEX))

    def shade(n_side: int) -> tuple[np.ndarray, np.ndarray]:
        x, y = _grid(n_side)
        hit, n, refl, ndv = _sphere(x, y)
        prod = np.tile(background, (n_side, n_side, 1))
        old = prod.copy()
        prod[hit] = nr.shade_pixels(basis, w, n, refl, ndv, coat=ClearCoat())
        old_s = fresnel_schlick(ndv, CLEAR_COAT_INDEX) / schlick_ref
        old[hit] = nr.shade_pixels(basis, base_w, n, refl, ndv) + old_s[:, None] * nr.shade_pixels(
            basis, gloss_w, n, refl, ndv
        )
        return prod, old

    prod, old = shade(SIZE * SUPER)
    box = (SIZE, SUPER, SIZE, SUPER, 3)
    centre, _ = shade(SIZE)
    return prod.reshape(box).mean(axis=(1, 3)), centre, old.reshape(box).mean(axis=(1, 3))


def plastic_closed_form(env: Environment, coat: Coat) -> tuple[np.ndarray, np.ndarray]:
    """Closed forms (P, 3) at the pixel centres of the two coat models over a Lambert base, by brute-force
    integration of the map (box-filtered to 128 wide): the mirror term F_o L(R) plus

    * the exit-only coat (the product before its coat-transmitted diffuse map): (1 − F_o) ρ E(N),
      E(N) = ∫ L (N·ω)⁺ dω / π (irradiance / π);
    * Mitsuba's ``plastic`` (``nonlinear`` false): (1 − F_o) ρ E_F(N) / (η² (1 − F_dr,int)), E_F(N) =
      ∫ L (1 − F(N·ω)) (N·ω)⁺ dω / π: light entering the coat is attenuated by its Fresnel F_i as well.

    In a uniform map both bases equal (1 − F_o) ρ L: η²(1 − F_dr,int) = 1 − F_dr,ext, the cosine-weighted
    mean of 1 − F_i. The ratio of the two, per band, is what the exit-only coat's one difference predicts
    (the product now draws the second: ``ClearCoat.entry_scale``, ``prefilter.coat_diffuse_map``)."""
    from station.model.fresnel import fresnel_dielectric

    eta = CLEAR_COAT_INDEX
    small = env.downsampled(128).equirect.astype(float)
    h, w = small.shape[:2]
    dirs = equirect_directions(h, w).reshape(-1, 3)
    omega = np.broadcast_to(equirect_solid_angles(h, w), (h, w)).reshape(-1)
    rad = small.reshape(-1, 3)
    mu = np.linspace(0.0, 1.0, 20001)
    f_mu = fresnel_dielectric(mu, eta) * 2.0 * mu
    f_dr_ext = float(np.sum((f_mu[1:] + f_mu[:-1]) * 0.5 * np.diff(mu)))
    f_dr_int = 1.0 - (1.0 - f_dr_ext) / eta**2
    x, y = _grid(SIZE)
    _hit, n, refl, ndv = _sphere(x, y)
    cos = np.maximum(n @ dirs.T, 0.0)
    e_plain = (cos * omega) @ rad / np.pi
    e_fres = ((1.0 - fresnel_dielectric(cos, eta)) * cos * omega) @ rad / np.pi
    f_o = fresnel_dielectric(ndv, eta)[:, None]
    mirror = f_o * env.radiance(refl)
    base = (1.0 - f_o) * coat.diffuse
    return mirror + base * e_plain, mirror + base * e_fres / (eta**2 * (1.0 - f_dr_int))


def luminance(img: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance of linear sRGB radiance (..., 3)."""
    return img @ REC709_LUMINANCE


def mean_de00(a: np.ndarray, b: np.ndarray, white: float) -> float:
    """Mean CIEDE2000 between two radiance arrays (P, 3), Lab of radiance / *white*."""
    return float(np.mean(delta_e(linear_srgb_to_lab(a / white), linear_srgb_to_lab(b / white), "cie2000")))


def compare(env_name: str, env: Environment, basis: prefilter.PrefilteredBasis, coat: Coat) -> list[Case]:
    """Cases of one (environment, coat): per band ratios and the per-image ΔE00, with Mitsuba's floor."""
    ndv, mask = pixel_geometry()
    ref0, ref1 = (mitsuba_image(env.equirect, coat, s)[mask] for s in SEEDS)
    prod, centre, old = (a[mask] for a in product_image(basis, env, coat))
    white = float(luminance(env.mean_radiance()))
    lum = {k: luminance(v) for k, v in {"m0": ref0, "m1": ref1, "p": prod, "c": centre, "b": old}.items()}
    if coat.diffuse > 0.0:
        lum["cp"], lum["cm"] = (luminance(a) for a in plastic_closed_form(env, coat))
    label = f"{env_name}, {coat.name} ({coat.bsdf})"
    cases = []
    for lo, hi in BANDS:
        sel = (ndv >= lo) & (ndv < hi)
        med = {k: float(np.median(v[sel])) for k, v in lum.items()}
        m = med["m0"]
        closed = (
            f"; closed forms, exit-only coat / plastic {med['cp'] / med['cm']:.3f}" if "cp" in med else ""
        )
        cases.append(
            Case(
                f"{label}, N·V {lo:.2f}–{hi:.2f}: product / Mitsuba",
                f"{int(sel.sum())} px",
                med["p"] / m,
                "ratio",
                f"floor (Mitsuba seed 1 / 0) {med['m1'] / m:.4f}; Mitsuba {m:.4g}; pixel centre "
                f"{med['c'] / m:.3f}×; baseline {med['b'] / m:.3f}×{closed}",
            )
        )
    cases.append(
        Case(
            f"{label}: mean ΔE00 product against Mitsuba",
            f"{SIZE}x{SIZE}",
            mean_de00(ref0, prod, white),
            "ΔE00",
            f"floor (Mitsuba seed 0 against 1) {mean_de00(ref0, ref1, white):.3f}; pixel centre "
            f"{mean_de00(ref0, centre, white):.3f}; baseline {mean_de00(ref0, old, white):.3f}",
        )
    )
    if env_name == "furnace":
        top = float(luminance(prod).max())
        cases.append(
            Case(
                f"{label}: brightest pixel (furnace, ≤ 1)",
                f"{SIZE}x{SIZE}",
                top,
                "radiance",
                f"Mitsuba {float(lum['m0'].max()):.4f}; baseline {float(lum['b'].max()):.4f}",
            )
        )
    return cases


def setup_text(orient: dict[str, float], cpu_s: float, wall_s: float) -> str:
    """The markdown under the table: the set-up, the orientation check and the mapping."""
    import mitsuba as mi

    alphas = ", ".join(
        f"{c.gloss:g} GU → α {lobe_from_gloss(c.gloss).ward_alpha:.4f}"
        for c in COATS
        if c.bsdf == "roughplastic"
    )
    offsets = "; ".join(f"{k} {v:.2f} px" for k, v in orient.items())
    return f"""`python -m bench.coat_mitsuba`: Mitsuba {mi.__version__} (`scalar_rgb`, `direct` integrator,
{SPP} stratified spp, seeds {SEEDS[0]} and {SEEDS[1]}; a bench-only extra) against the product
(`numpy_renderer.shade_pixels` with `ClearCoat`, n = {CLEAR_COAT_INDEX}) on a unit sphere, orthographic,
{SIZE} × {SIZE}, box pixels; the product averages {SUPER} × {SUPER} sub-pixel samples per pixel (misses
see the environment along −Z, as Mitsuba's rays do). Environments: uniform radiance 1 ("furnace") and the
shared HDRs at {ENV_WIDTH} × {ENV_WIDTH // 2}, the same array in both renderers. Orientation check (mirror
sphere, three coloured blobs, largest centroid offset Mitsuba − product): {offsets}. Coats: `plastic`
over black and over a 0.8 Lambert base (`nonlinear` false); `roughplastic` over black, Beckmann, α = the
product's Ward α of the gloss (`lobe_from_gloss(g).ward_alpha`: {alphas}). Bands by N·V at the pixel
centre; ratio of the band's median luminance; "floor" Mitsuba seed 1 over seed 0; "pixel centre" the
product shaded once per pixel centre; "baseline" the coat before the physical one (Schlick normalised at
60° onto the design's share, base untouched), supersampled the same way; "closed forms, exit-only coat /
plastic" (white base) the map-integrated closed form of the physical coat before its coat-transmitted
diffuse map (1 − F(N·V) on the base, the light entering unattenuated) over Mitsuba's plastic's. ΔE00: mean over the sphere's
pixels of CIEDE2000 between Lab of radiance / the environment's mean luminance. Run time {wall_s:.0f} s
wall, {cpu_s:.0f} s CPU (shared machine, loaded)."""


def main() -> None:
    t_cpu, t_wall = time.process_time(), time.perf_counter()
    orient = orientation_check()
    print("orientation (px):", orient)
    if orient["rolled (used)"] > 1.0:
        raise SystemExit(f"environment orientation differs between the renderers: {orient}")
    cases: list[Case] = []
    for name, env in environments().items():
        exps = lf.fit_design(FaceFlopTravelGloss((0.0,) * 3, (0.0,) * 3, None, 100.0, "x")).exponents
        basis = prefilter.prefilter_basis(env, exps, engine="numpy", max_size=64)
        for coat in COATS:
            new = compare(name, env, basis, coat)
            for c in new:
                print(c.line(), c.note)
            cases += new
    text = setup_text(orient, time.process_time() - t_cpu, time.perf_counter() - t_wall)
    write_section("coat_mitsuba", "Clear coat against Mitsuba 3 (bench/coat_mitsuba.py)", cases, text)


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "coat_mitsuba")
    main()
