"""The physical clear coat against an independent renderer: Mitsuba 3 (``scalar_rgb``, ``plastic`` BSDF).

Run: ``.venv/bin/python -m bench.coat_mitsuba`` (needs ``pip install mitsuba``: a bench-only extra, never a
runtime dependency). A unit sphere seen orthographically along −Z (64 × 64 pixels, 64 samples per pixel,
Mitsuba's ``direct`` integrator: the environment reflected once), lit by two environments that depend on
the height ω_y alone (so the two renderers' azimuth conventions cannot differ):

* ``furnace``: uniform radiance 1 (the white-furnace test);
* ``sky``: L(ω) = 0.3 + 0.7 max(ω_y, 0)² + 0.05 (grey; a bright zenith over a dark ground).

Paints: a black 100 GU coat (Mitsuba: ``plastic``, int_ior 1.5, diffuse 0 — a smooth dielectric over black)
and a white one (diffuse 0.8 under the coat; Mitsuba's plastic adds the coat's internal re-reflections,
(1 − F_i)(1 − F_o) ρ / (π η² (1 − F_dr ρ)), which the product's (1 − F(N·V)) ρ/π leaves out).

Product: ``numpy_renderer.shade_pixels`` with the fitted weights of the 100 GU design and
:class:`station.model.gloss.ClearCoat` (exact Fresnel, base × (1 − F)). Baseline, same run: the coat as
it was before (Schlick's F normalised at 60° onto the design's share: s = F_Schlick(N·V)/F_Schlick(60°)
on the gloss, base untouched).

Reported per N·V band: median pixel radiance of Mitsuba, the product and the baseline, and the ratio to
Mitsuba.
"""

from __future__ import annotations

import numpy as np

from bench._report import Case, write_section
from station.model import FaceFlopTravelGloss
from station.model.gloss import ClearCoat, fresnel_schlick
from station.render import lobe_fit as lf
from station.render import numpy_renderer as nr
from station.render import prefilter
from station.render.environment import Environment
from station.render.truth import equirect_directions

SIZE = 64
SPP = 64
HEIGHT = 128
BANDS = ((0.9, 1.0), (0.5, 0.6), (0.3, 0.4), (0.1, 0.2), (0.02, 0.05))
SETUP = f"""`python -m bench.coat_mitsuba` (Mitsuba 3, `scalar_rgb`, `plastic` int_ior 1.5, `direct` integrator,
{SPP} spp; a bench-only extra). Unit sphere, orthographic, {SIZE} × {SIZE}; environments that depend on ω_y
only (uniform radiance 1, "furnace"; a grey sky 0.35 + 0.7 max(ω_y, 0)²); a 100 GU paint over a black and
over a 0.8 Lambert base. Median green radiance per N·V band; "product" the physical coat (`ClearCoat`,
exact Fresnel, base × (1 − F)), "baseline" the coat before it (Schlick normalised at 60° onto the
design's share, base untouched), same run; ratios to Mitsuba."""


def environments() -> dict[str, np.ndarray]:
    """The two environments, equirect (H, 2H, 3) float32, +Y up (θ from +Y down the rows)."""
    y = equirect_directions(HEIGHT, 2 * HEIGHT)[..., 1]
    sky = 0.35 + 0.7 * np.maximum(y, 0.0) ** 2
    return {
        "furnace": np.ones((HEIGHT, 2 * HEIGHT, 3), np.float32),
        "sky": np.repeat(sky[..., None], 3, axis=2).astype(np.float32),
    }


def pixel_geometry() -> tuple[np.ndarray, np.ndarray]:
    """Normals (P, 3) and the mask (SIZE, SIZE) of the orthographic unit sphere, row 0 at +Y."""
    c = (np.arange(SIZE) + 0.5) / SIZE * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)
    r2 = x * x + y * y
    mask = r2 < 1.0
    n = np.stack([x, y, np.sqrt(np.maximum(1.0 - r2, 0.0))], axis=-1)
    return n[mask], mask


def mitsuba_image(env: np.ndarray, diffuse: float) -> np.ndarray:
    """Mitsuba 3 render (SIZE, SIZE, 3) of the coated sphere in *env*."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "direct", "emitter_samples": 4, "bsdf_samples": 4},
            "sensor": {
                "type": "orthographic",
                "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"}},
                "sampler": {"type": "stratified", "sample_count": SPP},
            },
            "emitter": {"type": "envmap", "bitmap": mi.Bitmap(np.array(env, dtype=np.float32))},
            "sphere": {
                "type": "sphere",
                "bsdf": {
                    "type": "plastic",
                    "int_ior": 1.5,
                    "ext_ior": 1.0,
                    "diffuse_reflectance": {"type": "rgb", "value": [diffuse] * 3},
                    "nonlinear": False,
                },
            },
        }
    )
    return np.asarray(mi.render(scene), dtype=float)[..., :3]


def product_pixels(env: np.ndarray, diffuse: float, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(product, baseline) radiance (P, 3) of the 100 GU paint over a Lambert base of *diffuse*."""
    design = FaceFlopTravelGloss((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), None, 100.0, "black 100 GU")
    w = lf.fit_design(design)
    from station.render.weights import LobeWeights

    w = LobeWeights(w.exponents, np.full(3, diffuse / np.pi), w.k_dd, w.k_g)
    basis = prefilter.prefilter_basis(Environment("bench", env), w.exponents, engine="numpy", max_size=64)
    view = np.array([0.0, 0.0, 1.0])
    ndv = normals @ view
    reflect = 2.0 * ndv[:, None] * normals - view
    coat = ClearCoat()
    product = nr.shade_pixels(basis, w, normals, reflect, ndv, coat=coat)
    base = nr.shade_pixels(
        basis, LobeWeights(w.exponents, w.k_d, w.k_dd, np.zeros_like(w.k_g)), normals, reflect, ndv
    )
    gloss = nr.shade_pixels(
        basis, LobeWeights(w.exponents, np.zeros(3), w.k_dd, w.k_g), normals, reflect, ndv
    )
    old = fresnel_schlick(ndv, 1.5) / float(fresnel_schlick(0.5, 1.5))
    return product, base + old[:, None] * gloss


def _band_cases(name: str, diffuse: float, ndv: np.ndarray, images: tuple[np.ndarray, ...]) -> list[Case]:
    """Print the N·V bands of one (environment, base) and return them as report cases."""
    ref, ours, old = images
    cases = []
    for lo, hi in BANDS:
        sel = (ndv >= lo) & (ndv < hi)
        m, p, b = (float(np.median(a[sel, 1])) for a in (ref, ours, old))
        print(
            f"{name:8s} {diffuse:4.1f}   {lo:.2f}–{hi:.2f}   {m:8.4f}  {p:8.4f} ({p / m:5.3f})  {b:8.4f} ({b / m:5.3f})"
        )
        cases.append(
            Case(
                f"{name} base {diffuse:.1f}, N·V {lo:.2f}–{hi:.2f}: product / Mitsuba",
                f"{SIZE}x{SIZE}",
                p / m,
                "ratio",
                f"Mitsuba {m:.4f}, product {p:.4f}; baseline {b:.4f} ({b / m:.3f}×)",
            )
        )
    m, p, b = (float(a[:, 1].max()) for a in (ref, ours, old))
    print(f"{name:8s} {diffuse:4.1f}   max pixel   {m:8.4f}  {p:8.4f}          {b:8.4f}")
    note = f"Mitsuba {m:.4f}, baseline {b:.4f}"
    return [
        *cases,
        Case(f"{name} base {diffuse:.1f}, max pixel: product", f"{SIZE}x{SIZE}", p, "radiance", note),
    ]


def main() -> None:
    normals, mask = pixel_geometry()
    ndv = normals[:, 2]
    print("env      base   N·V band    Mitsuba   product  (ratio)   baseline (ratio)")
    cases: list[Case] = []
    for name, env in environments().items():
        for diffuse in (0.0, 0.8):
            ref = mitsuba_image(env, diffuse)[mask]
            ours, old = product_pixels(env, diffuse, normals)
            cases += _band_cases(name, diffuse, ndv, (ref, ours, old))
    write_section(
        "coat_mitsuba",
        "Clear coat against Mitsuba 3 (bench/coat_mitsuba.py)",
        cases,
        SETUP,
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "coat_mitsuba")
    main()
