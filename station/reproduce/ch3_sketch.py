"""Thesis §3.7: the sketch fit of Fig. 3.20, its RMS measured by an independent re-render, and gloss.

Fig. 3.20: art made by rotating the hue of a rendering (HSV, as a paint program does) and fitted with
the point-light fit (:func:`station.design.sketch.fit_point_light`). The thesis reports an RMS of 2 ΔE
between the goal and "the rendering of the found material". Ours re-renders the fitted design with the
scene shader (:func:`station.design.scene.shade`) and takes the RMS ΔE*ab over every foreground pixel
that is not near white, the highlight included — independently of the fit's own ``rms_de``, which covers
only the pixels the fit used (highlight θ < 10°, near-white, edge and outlier pixels left out).

Gloss: the fit's default, ``gloss="highlight"`` (the gloss whose rendering reproduces the art's pixels
within 15° of specular, :func:`station.design.sketch.fit_highlight_gloss`), read off art rendered at
5–95 GU against the gloss the art was made with; beside it the thesis's contrast-gloss rule (§3.5.3,
:func:`station.design.moodboard.contrast_gloss` on the same pixels, ``gloss="contrast"``), which is not
monotone, and ``gloss="fit"`` (candidate highlights subtracted before eq 3.7.2, blind to highlights
inside the 10° it leaves out).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from station.design import artwork
from station.design.scene import shade, sphere_scene, srgb_decode, srgb_encode
from station.design.sketch import fit_point_light, rms_delta_e
from station.model import FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab
from station.reproduce.core import ExperimentResult, Figure, Quantity

#: The view the art is painted over: a point-lit sphere, 64 px.
SIZE_PX = 64
#: The paint the artist starts from (the initial image).
INITIAL = FaceFlopTravelGloss((85.0, 0.0, 0.0), (40.0, 0.0, 0.0), 70.0, 50.0, "silver")
#: Goal designs (in sRGB at every angle) whose hue the art rotates.
DESIGNS = (
    FaceFlopTravelGloss((70.0, 20.0, -25.0), (35.0, 10.0, -30.0), 80.0, 50.0, "violet metallic"),
    FaceFlopTravelGloss((60.0, -25.0, 20.0), (28.0, -10.0, 12.0), 60.0, 50.0, "green metallic"),
    FaceFlopTravelGloss((75.0, 5.0, 35.0), (40.0, 12.0, 20.0), 95.0, 50.0, "gold metallic"),
    FaceFlopTravelGloss((55.0, 35.0, 10.0), (22.0, 18.0, 2.0), 70.0, 50.0, "red metallic"),
)
HUE_ROTATIONS_DEG = (30.0, 90.0, 180.0)
ART_GLOSS_GU = (5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 95.0)
#: The issue's near-white case: a 90 GU silver (the contrast rule read 0 GU).
SILVER_90 = FaceFlopTravelGloss((85.0, 0.0, 0.0), (40.0, 0.0, 0.0), 70.0, 90.0, "silver")


def _lab(encoded: np.ndarray) -> np.ndarray:
    return linear_srgb_to_lab(np.clip(srgb_decode(encoded), 1e-6, None))


def rerender_rms(scene_size: int, art: np.ndarray, design: FaceFlopTravelGloss) -> float:
    """RMS ΔE*ab between *art* and *design* re-rendered on the sphere, both 8-bit-range sRGB, over the
    foreground pixels that are not near white (every channel ≥ 0.95)."""
    scene = sphere_scene(scene_size)
    got = srgb_encode(shade(scene, design))
    m = scene.mask & (np.min(art, axis=-1) < 0.95)
    return rms_delta_e(_lab(got[m]), _lab(art[m]))


def fig320_cases(gloss: str) -> list[tuple[float, float]]:
    """(fit's own RMS, independent re-render RMS) for every design × hue rotation."""
    scene = sphere_scene(SIZE_PX)
    initial = srgb_encode(shade(scene, INITIAL))
    out = []
    for d in DESIGNS:
        goal = srgb_encode(shade(scene, d))
        for hue in HUE_ROTATIONS_DEG:
            art = artwork.rotate_hue(goal, hue, scene.mask)
            fit = fit_point_light(scene, art, initial, gloss=gloss)
            out.append((float(fit.rms_de), rerender_rms(SIZE_PX, art, fit.design)))
    return out


def gloss_readings(gloss: str, design: FaceFlopTravelGloss = DESIGNS[0]) -> list[float]:
    """The gloss (GU) the fit reads off art rendered at each of :data:`ART_GLOSS_GU`."""
    scene = sphere_scene(SIZE_PX)
    initial = srgb_encode(shade(scene, DESIGNS[1]))
    return [
        float(
            fit_point_light(
                scene, srgb_encode(shade(scene, design.replace(gloss_gu=g))), initial, gloss=gloss
            ).design.gloss_gu
        )
        for g in ART_GLOSS_GU
    ]


def silver_reading(gloss: str) -> float:
    """The gloss (GU) the fit reads off a 90 GU silver (:data:`SILVER_90`) painted over the green design."""
    scene = sphere_scene(SIZE_PX)
    initial = srgb_encode(shade(scene, DESIGNS[1]))
    art = srgb_encode(shade(scene, SILVER_90))
    return float(fit_point_light(scene, art, initial, gloss=gloss).design.gloss_gu)


def _decreases(values: Sequence[float], slack: float = 0.5) -> int:
    return sum(1 for a, b in itertools.pairwise(values) if b < a - slack)


def _picture(out_dir: Path, highlight: list[float], contrast: list[float], fitted: list[float]) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene = sphere_scene(SIZE_PX)
    d = DESIGNS[0]
    goal = srgb_encode(shade(scene, d))
    art = artwork.rotate_hue(goal, 90.0, scene.mask)
    fit = fit_point_light(scene, art, srgb_encode(shade(scene, INITIAL)), gloss="default")
    found = srgb_encode(shade(scene, fit.design))
    diff = np.clip(0.5 + 4.0 * (found - art), 0.0, 1.0)
    fig, axes = plt.subplots(
        1, 5, figsize=(14, 3.0), constrained_layout=True, gridspec_kw={"width_ratios": [1, 1, 1, 1, 1.6]}
    )
    for ax, img, title in zip(
        axes[:4],
        (srgb_encode(shade(scene, INITIAL)), art, found, diff),
        (
            "initial",
            "goal (hue +90°)",
            f"found: re-render RMS {rerender_rms(SIZE_PX, art, fit.design):.2f}",
            "difference × 4",
        ),
        strict=True,
    ):
        ax.imshow(np.clip(img, 0, 1))
        ax.set_title(title, fontsize=8)
        ax.axis("off")
    axes[4].plot(ART_GLOSS_GU, ART_GLOSS_GU, "k:", lw=1, label="art gloss")
    axes[4].plot(ART_GLOSS_GU, highlight, "D-", label='gloss="highlight" (default)')
    axes[4].plot(ART_GLOSS_GU, contrast, "o-", label="contrast gloss (§3.5.3)")
    axes[4].plot(ART_GLOSS_GU, fitted, "s-", label='gloss="fit"')
    axes[4].set_xlabel("gloss of the art (GU)")
    axes[4].set_ylabel("gloss read (GU)")
    axes[4].legend(fontsize=7)
    path = out_dir / "ch3-fig3.20.png"
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return Figure(
        "3.20", path, "Fig. 3.20 on our code (gloss 50 GU) and the gloss read off art of known gloss."
    )


def fig320(out_dir: Path | None) -> ExperimentResult:
    """Fig. 3.20 with the RMS of an independent re-render; contrast gloss against art gloss."""
    t0 = time.perf_counter()
    default = fig320_cases("default")
    highlight = fig320_cases("highlight")
    read_highlight = gloss_readings("highlight")
    read_contrast = gloss_readings("contrast")
    read_fit = gloss_readings("fit")
    silver = silver_reading("highlight")
    quantities = (
        *_rerender_quantities(default, highlight),
        *_gloss_quantities(read_highlight, read_contrast, read_fit, silver),
    )
    figures = (_picture(out_dir, read_highlight, read_contrast, read_fit),) if out_dir is not None else ()
    notes = (
        f"{len(DESIGNS)} designs × hue rotations {', '.join(f'{h:g}°' for h in HUE_ROTATIONS_DEG)} on a "
        f"{SIZE_PX}-px point-lit sphere. Fit's own RMS / re-render RMS, highlight gloss: "
        + ", ".join(f"{s:.2f}/{r:.2f}" for s, r in highlight)
        + ". Gloss read for art at "
        + ", ".join(f"{g:g}" for g in ART_GLOSS_GU)
        + ' GU: gloss="highlight" '
        + ", ".join(f"{v:.1f}" for v in read_highlight)
        + "; contrast "
        + ", ".join(f"{v:.0f}" for v in read_contrast)
        + '; gloss="fit" '
        + ", ".join(f"{v:.0f}" for v in read_fit)
        + f". A 90 GU silver reads {silver:.1f} GU (highlight)."
    )
    return ExperimentResult("ch3-fig3.20", quantities, figures, notes, time.perf_counter() - t0)


def _rerender_quantities(
    default: Sequence[tuple[float, float]], highlight: Sequence[tuple[float, float]]
) -> tuple[Quantity, ...]:
    """Fig. 3.20's RMS (ΔE*ab) by an independent re-render: *default* and *highlight* are (fit's own
    RMS, re-render RMS) per case, gloss 50 GU and gloss read off the highlight."""
    rr_default = [r for _, r in default]
    rr_highlight = [r for _, r in highlight]
    gap = max(r - s for s, r in highlight)
    excluded = (
        "the fit's own RMS covers only the pixels it fitted (highlight θ < 10°, near-white, edge and outlier "
        "pixels left out); what the colour curve misses next to the highlight shows only in the re-render"
    )
    return (
        Quantity(
            "3.20",
            "re-render RMS, gloss 50 GU (median of 12)",
            "ΔE*ab",
            2.0,
            float(np.median(rr_default)),
            0.0,
            mode="at_most",
            source="§3.7.4 'a RMS error of 2 ΔE'",
        ),
        Quantity(
            "3.20",
            "re-render RMS, highlight gloss (median of 12)",
            "ΔE*ab",
            2.0,
            float(np.median(rr_highlight)),
            0.0,
            mode="at_most",
            source="§3.7.4",
        ),
        Quantity(
            "3.20",
            "re-render RMS, highlight gloss (worst of 12)",
            "ΔE*ab",
            2.0,
            float(np.max(rr_highlight)),
            0.0,
            mode="at_most",
            source="§3.7.4",
            reason="hue-rotated art is not a design of the model: the colour curve fitted at θ ≥ 10° "
            "misses the art next to the highlight, which the re-render counts",
        ),
        Quantity(
            "3.20",
            "re-render RMS − the fit's own RMS, highlight gloss (worst)",
            "ΔE*ab",
            0.0,
            gap,
            0.25,
            reason=excluded,
            source="an RMS 'compared to the goal' is over the whole object",
        ),
    )


def _gloss_quantities(
    read_highlight: Sequence[float], read_contrast: Sequence[float], read_fit: Sequence[float], silver: float
) -> tuple[Quantity, ...]:
    """§3.5.3: gloss (GU) read off art rendered at :data:`ART_GLOSS_GU` by each rule, and the 90 GU silver."""
    sweep = [(a, r) for a, r in zip(ART_GLOSS_GU, read_highlight, strict=True) if 10.0 <= a <= 95.0]
    worst = max(abs(r - a) for a, r in sweep)
    return (
        Quantity(
            "§3.5.3",
            'gloss="highlight": falls where the art\'s gloss rises (steps of 5–95 GU)',
            "count",
            0,
            _decreases(read_highlight),
            0,
            source="a gloss estimate must rise with gloss",
        ),
        Quantity(
            "§3.5.3",
            'gloss="highlight": worst |read − art gloss| over 10–95 GU',
            "GU",
            0.0,
            worst,
            3.0,
            reference="art gloss",
            source="the gloss the art was rendered with",
        ),
        Quantity(
            "§3.5.3",
            'gloss="highlight": a 90 GU silver',
            "GU",
            90.0,
            silver,
            10.0,
            reference="art gloss",
            source="the issue's case: the contrast rule read 0 GU",
            reason="a near-white design clips its highlight at white: gloss values that leave the "
            "unclipped pixels alike cannot be told apart",
        ),
        Quantity(
            "§3.5.3",
            "contrast gloss (thesis rule): falls where the art's gloss rises",
            "count",
            0,
            _decreases(read_contrast),
            0,
            reason="the brightest 10 % of the pixels within 15° of specular: once the highlight is smaller "
            "than that tail the contrast falls as the gloss rises, and it saturates from 40 GU; the "
            'sketch fit reads gloss="highlight" by default and keeps this rule for comparison',
            source="a gloss estimate must rise with gloss",
        ),
        Quantity(
            "§3.5.3",
            'gloss="fit": falls where the art\'s gloss rises',
            "count",
            0,
            _decreases(read_fit),
            0,
            source="a gloss estimate must rise with gloss",
            reason="the candidate gloss list is coarse",
        ),
    )


#: The thesis's environment-lit fit: "several minutes" (read as 2 minutes, the least "several" can mean).
THESIS_ENV_FIT_S = 120.0


def environment_fit(out_dir: Path | None) -> ExperimentResult:
    """§3.7.5: the environment-lit fit's time (thesis: several minutes) and its RMS by re-rendering."""
    from station.design.scene import environment_sphere_scene, lobe_basis, shade_environment
    from station.design.sketch import fit_environment

    t0 = time.perf_counter()
    env = environment_sphere_scene(48)
    tb = time.perf_counter()
    basis = lobe_basis(env)
    basis_s = time.perf_counter() - tb
    initial = srgb_encode(shade_environment(env, INITIAL))
    times, rms = [], []
    for d in DESIGNS:
        art = artwork.rotate_hue(srgb_encode(shade_environment(env, d)), 90.0, env.mask)
        t = time.perf_counter()
        fit = fit_environment(basis, art, initial)
        times.append(time.perf_counter() - t)
        got = srgb_encode(shade_environment(env, fit.design))
        m = env.mask & (np.min(art, axis=-1) < 0.95)
        rms.append(rms_delta_e(_lab(got[m]), _lab(art[m])))
    quantities = (
        Quantity(
            "§3.7.5",
            "environment-lit fit, median of 4 (basis images prebuilt)",
            "s",
            THESIS_ENV_FIT_S,
            float(np.median(times)),
            0.0,
            mode="at_most",
            source="§3.7.5 'several minutes' (nonlinear search rendering the scene per guess)",
        ),
        Quantity(
            "§3.7.5",
            "basis images, built once per scene",
            "s",
            THESIS_ENV_FIT_S,
            basis_s,
            0.0,
            mode="at_most",
            source="§3.7.5",
        ),
        Quantity(
            "3.19",
            "environment-lit fit, re-render RMS (worst of 4)",
            "ΔE*ab",
            15.0,
            float(np.max(rms)),
            0.0,
            mode="at_most",
            source="§3.7.5: the traced-art match had 'a relatively high 15 ΔE'",
        ),
    )
    notes = (
        f"48-px sphere under 16 studio lights; basis images {basis_s * 1e3:.0f} ms once, then each fit "
        + ", ".join(f"{t * 1e3:.0f}" for t in times)
        + " ms; re-render RMS "
        + ", ".join(f"{r:.2f}" for r in rms)
        + " ΔE*ab (hue-rotated renderings: cleaner art than the thesis's traced markers, hence lower)."
    )
    return ExperimentResult("ch3-environment-fit", quantities, (), notes, time.perf_counter() - t0)


def traced(art: np.ndarray, mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Fig. 3.21-style art: hue rotated, shading partly flattened (marker fills), posterised, misregistered
    by up to 1.5 px (the scan's alignment) and blurred."""
    a = artwork.rotate_hue(art, float(rng.uniform(-180, 180)), mask)
    a = artwork.flatten_shading(a, float(rng.uniform(0.2, 0.6)), mask)
    a = artwork.posterise(a, int(rng.integers(8, 17)))
    a = artwork.misregister(a, float(rng.uniform(-1.5, 1.5)), float(rng.uniform(-1.5, 1.5)))
    return artwork.blur(a, float(rng.uniform(0.0, 1.0)))


def traced_art(out_dir: Path | None) -> ExperimentResult:
    """Fig. 3.21: traced, marker-filled art; the point-light fit and its re-render RMS (thesis: 14 ΔE)."""
    t0 = time.perf_counter()
    scene = sphere_scene(SIZE_PX)
    initial = srgb_encode(shade(scene, INITIAL))
    rng = np.random.default_rng(321)
    rms, failed = [], 0
    for d in DESIGNS:
        for _ in range(3):
            art = traced(srgb_encode(shade(scene, d)), scene.mask, rng)
            fit = fit_point_light(scene, art, initial, gloss="default")
            failed += int(fit.failed)
            rms.append(rerender_rms(SIZE_PX, art, fit.design))
    quantities = (
        Quantity(
            "3.21",
            "traced art: re-render RMS (median of 12)",
            "ΔE*ab",
            14.0,
            float(np.median(rms)),
            0.0,
            mode="at_most",
            source="§3.7.4: the traced, marker-filled art 'has a relatively high RMS error of 14 ΔE'",
        ),
        Quantity(
            "3.21",
            "traced art: fits that fail on the first try",
            "%",
            35.0,
            100.0 * failed / len(rms),
            10.0,
            source="§3.7.4 'tracing and scanning back … about 35 %' (a failure returns the diffuse colour)",
            reason="our traced art is synthetic; its failure share depends on how much shading it flattens",
        ),
    )
    notes = (
        f"Re-render RMS per fit: {', '.join(f'{r:.1f}' for r in rms)} ΔE*ab; {failed} of {len(rms)} fits flagged "
        "the shading as inconsistent and returned the diffuse fallback. Our traced art is synthetic "
        "(posterised, flattened, misregistered renderings), milder than hand-drawn markers."
    )
    return ExperimentResult("ch3-traced", quantities, (), notes, time.perf_counter() - t0)
