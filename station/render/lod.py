"""Level of detail: the least model a scene needs for a colour-difference tolerance (docs/design.md §4).

Given the designs on screen, the environment and the pixels (normals, views), :func:`choose_lod` picks

1. the fewest lobes m (shipped optimal bases, eq 2.3.4) whose lobe model stays within the tolerance of
   the ground truth (:mod:`station.render.truth`, the designed BRDF itself);
2. the smallest environment resolution (equirect width; a cube face is width/4) whose images stay
   within the tolerance of the full-resolution images, with m lobes;
3. the fewest anisotropic off-specular samples (eqs 2.5.4–2.5.7) whose images stay within the
   tolerance of the most-sampled image, when the caller renders anisotropy (an isotropic scene needs 1).
   :func:`choose_anisotropic_samples` makes the same choice for one design's anisotropy on its own (the
   GL renderer calls it per environment and anisotropy, and reports it as ``last_anisotropy``).

4. the whole choice measured once more against the ground truth, the way the renderers draw
   (``prefiltered-bent+lights`` by default; the anisotropy's error added in quadrature): "meets" only when
   that total is within the tolerance; a setting that misses it gives way to the default (the shipped
   lobe count, the full map) whenever that measures less, so a miss is never worse than the default.

Those steps judge sample pixels the caller passes, in a truth-engine mode. What the fronts use
(``station render --lod``, the service's ``lod_de``: :func:`station.render.scene_image.scene_lod`) is the
frame's level of detail, :func:`choose_frame_lod`: every candidate setting (:class:`FrameSetting`: lobes,
map width, anisotropic samples) is rendered small (PROBE_SIZE) by the frame's own renderer, mode and
scene, and its estimate is its p95 CIEDE2000 against the renderer's most accurate setting (MAX_LOBES
lobes, the full map, the most samples); "meets" only when estimate + FRAME_MARGIN_DE (a declared
calibration of the probe-to-truth gap, ``bench.lod_margin``) is within the tolerance, and no setting is
picked whose estimate exceeds the default's; when none meets, the default is drawn and the miss reported.

Each factor gets a share tolerance/√3 of the budget (errors of independent approximations add roughly
in quadrature), measured as the given percentile of CIEDE2000 over pixels and designs, Lab relative to
the scene's brightest white-Lambertian pixel. When even the richest setting misses its share the
richest is chosen and the choice says so: LOD never hides a miss.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.render import lobe_fit as lf
from station.render import truth as tr
from station.render import truth_lighting as tl
from station.render.errors import RenderInputError
from station.render.lobes import MAX_LOBES, basis_for_count, default_basis

#: Environment widths tried (equirect pixels; powers of two).
ENV_WIDTHS = (16, 32, 64, 128, 256, 512, 1024, 2048)
#: Anisotropic sample counts tried (odd, symmetric about the specular direction).
SAMPLE_COUNTS = (1, 3, 5, 9, 15, 25, 35, 49, 81)


@dataclass(frozen=True)
class LodChoice:
    """What :func:`choose_lod` chose, with the error of each factor (CIEDE2000 at the percentile)."""

    lobes: int
    exponents: tuple[float, ...]
    environment_width: int
    anisotropic_samples: int
    tolerance_de: float
    errors: dict[str, float] = field(default_factory=dict)
    met: bool = True
    notes: tuple[str, ...] = ()

    def describe(self) -> str:
        """One paragraph saying what was chosen and why."""
        share = self.tolerance_de / np.sqrt(3.0)
        parts = [
            f"{self.lobes} lobes (E = {', '.join(f'{e:.4g}' for e in self.exponents)}): "
            f"ΔE {self.errors.get('lobes', float('nan')):.2f} against ground truth",
            f"environment {self.environment_width}×{self.environment_width // 2} "
            f"(cube face {self.environment_width // 4}): ΔE {self.errors.get('environment', float('nan')):.2f} "
            "against full resolution",
            f"{self.anisotropic_samples} anisotropic sample(s): "
            f"ΔE {self.errors.get('anisotropy', 0.0):.2f} against the most-sampled image",
            f"all together ΔE {self.errors.get('total', float('nan')):.2f} against ground truth",
        ]
        verdict = "meets" if self.met else "MISSES"
        text = (
            f"Tolerance ΔE {self.tolerance_de:g} ({verdict}; share {share:.2f} each): "
            + "; ".join(parts)
            + "."
        )
        return text + ("" if not self.notes else " " + " ".join(self.notes))


def downsample_equirect(img: NDArray[np.float64], width: int) -> NDArray[np.float64]:
    """Solid-angle-weighted box filter of an equirect map to (width/2, width) (width divides the map's)."""
    h, w = img.shape[:2]
    return tl._box_downsample(img, tl.equirect_solid_angles(h, w), width)[0]


def _de(scene_white: float, ref: NDArray[np.float64], img: NDArray[np.float64], percentile: float) -> float:
    from station.model.colorimetry import linear_srgb_to_lab
    from station.model.difference import delta_e

    d = delta_e(linear_srgb_to_lab(ref / scene_white), linear_srgb_to_lab(img / scene_white), "cie2000")
    return float(np.percentile(d, percentile))


def _fewest_samples(
    render: Callable[[int], NDArray[np.float64]],
    white: float,
    share: float,
    percentile: float,
    sample_counts: Sequence[int],
) -> tuple[int, float]:
    """(fewest samples within *share* of the most-sampled image, its ΔE); the most when none is."""
    counts = sorted(sample_counts)
    if not counts or counts[0] < 1:
        raise RenderInputError("sample_counts", "sample counts >= 1", list(sample_counts))
    best = np.asarray(render(counts[-1]), dtype=float)
    for s in counts[:-1]:
        err = _de(white, best, np.asarray(render(s), dtype=float), percentile)
        if err <= share:
            return s, err
    return counts[-1], 0.0


@dataclass(frozen=True)
class AnisotropyChoice:
    """The anisotropic sample count :func:`choose_anisotropic_samples` chose, with its ΔE and why."""

    samples: int
    error_de: float  # CIEDE2000 at the percentile against the most-sampled image
    tolerance_de: float
    reason: str


def choose_anisotropic_samples(
    basis: Any,
    lobe: Any,
    normals: ArrayLike,
    views: ArrayLike,
    tolerance_de: float = 1.0,
    *,
    percentile: float = 95.0,
    sample_counts: Sequence[int] = SAMPLE_COUNTS,
    energy: str = "ward",
) -> AnisotropyChoice:
    """Fewest off-specular samples of *lobe* (:class:`station.render.anisotropy.WardLobe`) on *basis*
    whose gloss at the pixels (*normals*, *views*: (P, 3)) stays within tolerance/√3 of the most-sampled
    one (step 3 of the module docstring); Lab relative to the brightest white-Lambertian pixel
    (the exponent-1 map at the normals). An isotropic lobe (α_x = α_y) needs 1. *energy*: the lobe's
    energy convention (:data:`station.render.anisotropy.ENERGIES`)."""
    from station.render import anisotropy as an
    from station.render.cubemap import sample_cube

    if not (np.isfinite(tolerance_de) and tolerance_de > 0):
        raise RenderInputError("tolerance_de", "a CIEDE2000 tolerance > 0", tolerance_de)
    if not 0.0 < percentile <= 100.0:
        raise RenderInputError("percentile", "0 < percentile <= 100", percentile)
    n = np.asarray(normals, dtype=np.float64)
    v = np.asarray(views, dtype=np.float64)
    share = tolerance_de / np.sqrt(3.0)
    if lobe.spread <= 0.0:
        return AnisotropyChoice(1, 0.0, float(tolerance_de), "isotropic (alpha_x = alpha_y): 1 sample")
    white = float(sample_cube(basis.diffuse, n)[..., 1].max())  # as choose_lod: G of the white pixel
    s, err = _fewest_samples(
        lambda j: an.shade_anisotropic(basis, lobe, j, n, v, energy), white, share, percentile, sample_counts
    )
    most = max(sample_counts)
    why = (
        f"{s} anisotropic samples: ΔE {err:.2f} (p{percentile:g}) against {most} <= {share:.2f}"
        if s < most
        else f"{most} anisotropic samples: no fewer reach ΔE {share:.2f} against {most}"
    )
    return AnisotropyChoice(s, err, float(tolerance_de), why)


def _check_budget(tolerance_de: float, percentile: float) -> None:
    """Raise RenderInputError naming the field when the tolerance or the percentile is out of range."""
    if not (np.isfinite(tolerance_de) and tolerance_de > 0):
        raise RenderInputError("tolerance_de", "a CIEDE2000 tolerance > 0", tolerance_de)
    if not 0.0 < percentile <= 100.0:
        raise RenderInputError("percentile", "0 < percentile <= 100", percentile)


def _lod_scene(
    designs: Sequence[Any],
    environment: Any,
    normals: ArrayLike,
    views: ArrayLike,
    widths: Sequence[int],
    samples: int,
    quadrature_width: int,
    mode: str,
    percentile: float,
) -> tuple[_LodScene, list[int]]:
    """The scene the level of detail measures, and the environment widths that divide the map's own."""
    img = tl._as_equirect(environment)
    full_width = img.shape[1]
    usable = sorted(w for w in widths if w <= full_width and full_width % w == 0) or [full_width]
    brdfs = [d if isinstance(d, lf.DesignedBRDF) else lf.designed_brdf(d) for d in designs]
    scene = _LodScene(
        brdfs, img, normals, views, samples, min(quadrature_width, full_width), mode, percentile
    )
    return scene, usable


def choose_lod(
    designs: Sequence[Any],
    environment: Any,
    normals: ArrayLike,
    views: ArrayLike,
    tolerance_de: float = 1.0,
    *,
    percentile: float = 95.0,
    mode: str = "prefiltered-bent+lights",
    lobe_counts: Sequence[int] = tuple(range(1, MAX_LOBES + 1)),
    widths: Sequence[int] = ENV_WIDTHS,
    anisotropic: Callable[[int], NDArray[np.float64]] | None = None,
    sample_counts: Sequence[int] = SAMPLE_COUNTS,
    samples: int = 128,
    quadrature_width: int = 128,
) -> LodChoice:
    """Choose lobes, environment resolution and anisotropic samples for a scene (module docstring).

    Parameters
    ----------
    designs
        FaceFlopTravelGloss designs (or DesignedBRDFs) shown in the scene.
    environment
        Equirect map (H, 2H, 3) or an object with ``equirect``.
    normals, views
        (P, 3) unit normals and view directions of the scene's pixels (N·V > 0).
    tolerance_de
        Total CIEDE2000 budget (> 0).
    percentile
        Percentile of the per-pixel ΔE that must stay within each share (0–100).
    mode
        How the lobe model is evaluated (:data:`station.render.truth.LOBE_MODES`): default
        ``prefiltered-bent+lights``, the way the renderers draw (horizon tables, bent directionally
        diffuse lookups, lights shaded exactly); ``prefiltered``, ``prefiltered-lut`` or ``exact``.
    anisotropic
        Optional ``samples -> image (P, 3)`` renderer of the anisotropic scene; None for isotropic.
    """
    _check_budget(tolerance_de, percentile)
    if not designs:
        raise RenderInputError("designs", "at least one design", len(designs))
    ctx, widths = _lod_scene(
        designs, environment, normals, views, widths, samples, quadrature_width, mode, percentile
    )
    share = tolerance_de / np.sqrt(3.0)
    notes: list[str] = []
    # 1. lobes against ground truth
    chosen_m, lobe_err, met = ctx.fewest_lobes(lobe_counts, share)
    if not met:
        notes.append(
            f"No lobe count reaches ΔE {share:.2f} against ground truth in {mode} mode; "
            f"the most accurate ({chosen_m}) is used."
        )
    # 2. environment resolution against full resolution, chosen lobes
    chosen_w, env_err = ctx.smallest_width(widths, chosen_m, share)
    # 3. anisotropic samples against the most-sampled image
    chosen_s, aniso_err = 1, 0.0
    if anisotropic is not None:
        chosen_s, aniso_err = _fewest_samples(anisotropic, ctx.white, share, percentile, sample_counts)
    step_err = lobe_err[chosen_m]  # the lobe step's error (reported even when step 4 changes the choice)
    # 4. the whole choice against ground truth, and against the default (shipped lobes, full map)
    chosen_m, chosen_w, total = ctx.verify(chosen_m, chosen_w, aniso_err, float(tolerance_de), notes)
    met = total <= tolerance_de
    if not met:
        notes.append(f"The chosen setting measures ΔE {total:.2f} against ground truth: above the tolerance.")
    return LodChoice(
        chosen_m,
        basis_for_count(chosen_m).exponents,
        chosen_w,
        chosen_s,
        float(tolerance_de),
        {
            "lobes": step_err,
            "environment": env_err,
            "anisotropy": aniso_err,
            "total": total,
        },
        met,
        tuple(notes),
    )


class _LodScene:
    """The scene :func:`choose_lod` measures: truth, the lobe model at a lobe count and map width."""

    def __init__(
        self,
        brdfs: Sequence[lf.DesignedBRDF],
        img: NDArray[np.float64],
        normals: ArrayLike,
        views: ArrayLike,
        samples: int,
        quadrature_width: int,
        mode: str,
        percentile: float,
    ) -> None:
        self.brdfs, self.img, self.mode, self.percentile = list(brdfs), img, mode, percentile
        self.normals, self.views = normals, views
        self.samples, self.quadrature_width = samples, quadrature_width
        self.targets = lf.targets_from_brdfs(self.brdfs)
        self.scene = tr.TruthScene(img, normals, views, samples, quadrature_width)
        self.white = float(self.scene.white()[..., 1].max())
        self.truth = np.concatenate([self.scene.truth(b) for b in self.brdfs])
        self._scenes: dict[int, tr.TruthScene] = {img.shape[1]: self.scene}

    def scene_at(self, width: int) -> tr.TruthScene:
        """The pixels under the map box-filtered to *width* and held piecewise constant at full size (so
        only the lost environment detail differs, not the quadrature)."""
        if width not in self._scenes:
            f = self.img.shape[1] // width
            blocky = np.repeat(np.repeat(downsample_equirect(self.img, width), f, axis=0), f, axis=1)
            self._scenes[width] = tr.TruthScene(
                blocky, self.normals, self.views, self.samples, self.quadrature_width
            )
        return self._scenes[width]

    def images(self, m: int, width: int) -> NDArray[np.float64]:
        """The lobe model of every design with the m-lobe basis, on the map at *width*, in the mode."""
        rep = lf.fit_targets(self.targets, basis_for_count(m))
        sc = self.scene_at(width)
        return np.concatenate([sc.lobes(rep.weights(i), self.mode) for i in range(len(self.brdfs))])

    def error(self, ref: NDArray[np.float64], img: NDArray[np.float64]) -> float:
        """CIEDE2000 at the percentile, Lab relative to the scene's white."""
        return _de(self.white, ref, img, self.percentile)

    def fewest_lobes(self, counts: Sequence[int], share: float) -> tuple[int, dict[int, float], bool]:
        """(fewest lobes within *share* of the truth, errors so far, whether one was); else the best."""
        errors: dict[int, float] = {}
        full = self.img.shape[1]
        for m in sorted(counts):
            errors[m] = self.error(self.truth, self.images(m, full))
            if errors[m] <= share:
                return m, errors, True
        return min(errors, key=errors.__getitem__), errors, False

    def smallest_width(self, widths: Sequence[int], m: int, share: float) -> tuple[int, float]:
        """(smallest map width whose m-lobe images lie within *share* of full resolution, its error)."""
        full = self.img.shape[1]
        ref = self.images(m, full)
        for w in widths:
            if w == full:
                break
            err = self.error(ref, self.images(m, w))
            if err <= share:
                return w, err
        return full, 0.0

    def verify(
        self, m: int, width: int, aniso_err: float, tolerance: float, notes: list[str]
    ) -> tuple[int, int, float]:
        """Measure the chosen (m, width) against the truth, the anisotropy's error added in quadrature;
        when it misses *tolerance* and the default (shipped lobe count, full map) measures less, choose
        the default instead. Returns (lobes, width, total error)."""
        full = self.img.shape[1]
        chosen = float(np.hypot(self.error(self.truth, self.images(m, width)), aniso_err))
        m_def = default_basis().size
        if (m, width) == (m_def, full) or chosen <= tolerance:
            return m, width, chosen
        default = float(np.hypot(self.error(self.truth, self.images(m_def, full)), aniso_err))
        if default < chosen:
            notes.append(
                f"The reduced setting ({m} lobes, map {width}) measures ΔE {chosen:.2f}, the default "
                f"({m_def} lobes, full map) {default:.2f}: the default is used."
            )
            return m_def, full, default
        return m, width, chosen


# --------------------------------------------------------------------------------------------------------
# Level of detail of the rendered frame: what every front (``station render --lod``, the service's render
# route) uses. The steps above judge sample pixels in a truth-engine mode; the frame is drawn by the GL or
# NumPy renderer, so the frame's level of detail renders each candidate setting with that renderer.

#: Probe size (pixels, square): candidates are rendered this large (never larger than the frame).
PROBE_SIZE = 32
#: Lobe counts (shipped bases, :func:`station.render.lobes.basis_for_count`) the frame's level of detail tries.
FRAME_LOBES = (1, 2, 3, 5)
#: Environment widths (equirect pixels) it tries below the frame's own map.
FRAME_WIDTHS = (32, 64, 128)
#: Declared calibration (``python -m bench.lod_margin``): the largest amount by which a frame's p95
#: CIEDE2000 against the truth engine exceeded its probe estimate (against the renderer's most accurate
#: setting) over the training scenes (design-database paints; booth, overcast, sky; standard views; GL and
#: NumPy engines), rounded up to 0.05. Checked, not re-fitted, on held-out scenes (demo-library paints,
#: an HDR sunrise, close-ups, near-mirror gloss, anisotropic paints) by ``tests/render/test_lod_frame.py``.
FRAME_MARGIN_DE = 1.75


@dataclass(frozen=True)
class FrameSetting:
    """One level-of-detail setting of a frame. ``lobes``: the shipped basis of that many lobes (None: the
    shipped default basis); ``environment_width``: equirect width (pixels) the map is box-filtered to (None:
    the frame's own map); ``anisotropic_samples``: off-specular samples (None: the renderer's own choice)."""

    lobes: int | None = None
    environment_width: int | None = None
    anisotropic_samples: int | None = None

    def label(self) -> str:
        """Short text, e.g. ``3 lobes, map 64, 9 samples``."""
        lobes = "default lobes" if self.lobes is None else f"{self.lobes} lobes"
        width = "full map" if self.environment_width is None else f"map {self.environment_width}"
        text = f"{lobes}, {width}"
        if self.anisotropic_samples is not None:
            text += f", {self.anisotropic_samples} samples"
        return text


#: The frame's default setting: the shipped default basis on the frame's own map.
DEFAULT_SETTING = FrameSetting()


@dataclass(frozen=True)
class FrameLodChoice:
    """What :func:`choose_frame_lod` chose. ``estimate_de``: p95 CIEDE2000 of the chosen setting's probe
    against the reference probe (the renderer's most accurate setting); ``default_estimate_de``: the same
    for the default; ``margin_de``: the declared probe-to-truth margin; ``met``: estimate + margin within
    ``tolerance_de``; ``probes``: every setting rendered with its estimate, in the order tried."""

    setting: FrameSetting
    estimate_de: float
    default_estimate_de: float
    margin_de: float
    tolerance_de: float
    met: bool
    reference: FrameSetting
    probes: tuple[tuple[FrameSetting, float], ...]
    probe_size: int
    notes: tuple[str, ...] = ()

    def describe(self) -> str:
        """One paragraph saying what was chosen and why."""
        verdict = "meets" if self.met else "MISSES"
        text = (
            f"Tolerance ΔE {self.tolerance_de:g} ({verdict}): {self.setting.label()}, estimated ΔE "
            f"{self.estimate_de:.2f} + margin {self.margin_de:.2f} = {self.estimate_de + self.margin_de:.2f} "
            f"(default {self.default_estimate_de:.2f}), measured on {self.probe_size}² probes of the "
            f"renderer against its most accurate setting ({self.reference.label()})."
        )
        return text + ("" if not self.notes else " " + " ".join(self.notes))


def frame_error(
    reference: ArrayLike,
    image: ArrayLike,
    white: float,
    mask: ArrayLike | None = None,
    percentile: float = 95.0,
) -> float:
    """CIEDE2000 at *percentile* (%) of *image* against *reference* (linear sRGB (H, W, 3)) over the pixels
    of *mask* (all when None), Lab relative to the white *white* (linear luminance of the scene's white)."""
    from station.model.colorimetry import linear_srgb_to_lab
    from station.model.difference import delta_e

    ref = np.asarray(reference, dtype=np.float64)
    img = np.asarray(image, dtype=np.float64)
    if ref.shape != img.shape:
        raise RenderInputError("image", f"an image of shape {ref.shape}", img.shape)
    if mask is not None:
        sel = np.asarray(mask, dtype=bool)
        ref, img = ref[sel], img[sel]
    if ref.size == 0:
        raise RenderInputError("mask", "at least one pixel", 0)
    d = delta_e(linear_srgb_to_lab(ref / white), linear_srgb_to_lab(img / white), "cie2000")
    return float(np.percentile(d, percentile))


def scene_white(environment: Any) -> float:
    """Luminance (G, linear) of the scene's white: the brightest white Lambertian pixel over a sphere in
    *environment* (equirect or an object with ``equirect``), by the truth engine's quadrature."""
    img = tl._as_equirect(environment)
    n, v = tr.sphere_pixels(8)
    scene = tr.TruthScene(img, n, v, 16, min(64, img.shape[1]))
    return float(scene.white()[..., 1].max())


def frame_candidates(
    full_width: int,
    lobes: Sequence[int] = FRAME_LOBES,
    widths: Sequence[int] = FRAME_WIDTHS,
) -> list[FrameSetting]:
    """The reduced settings tried, cheapest first (fewer lobes, then smaller maps): every lobe count of
    *lobes* on every width of *widths* below *full_width* and on the full map."""
    usable = [w for w in sorted(widths) if w < full_width and full_width % w == 0]
    return [FrameSetting(m, w) for m in sorted(lobes) for w in [*usable, None]]


def choose_frame_lod(
    probe: Callable[[FrameSetting], NDArray[np.float64]],
    white: float,
    tolerance_de: float,
    candidates: Sequence[FrameSetting],
    *,
    mask: ArrayLike | None = None,
    anisotropic: bool = False,
    margin_de: float = FRAME_MARGIN_DE,
    percentile: float = 95.0,
    probe_size: int = PROBE_SIZE,
) -> FrameLodChoice:
    """Choose the frame's setting from what the renderer draws (module docstring, frame section).

    *probe* renders a setting with the frame's own renderer, mode and scene at the probe size (linear
    (H, W, 3)); the reference is the renderer's most accurate setting (MAX_LOBES lobes, the full map, the
    most anisotropic samples when *anisotropic*). Each setting's estimate is the p95 CIEDE2000 (*percentile*)
    of its probe against the reference over *mask* (Lab relative to *white*). The choice is the first of
    *candidates* (cheapest first), then the fewest anisotropic samples, whose estimate + *margin_de* is
    within *tolerance_de* and whose estimate does not exceed the default's; else the default, if it meets;
    else the default, reported as a miss. Below the margin (*tolerance_de* < *margin_de*) no candidate can
    meet, and only the reference and the default are drawn. Deterministic: no time budget enters it."""
    _check_budget(tolerance_de, percentile)
    if not (np.isfinite(margin_de) and margin_de >= 0):
        raise RenderInputError("margin_de", "a margin >= 0 (CIEDE2000)", margin_de)
    if not (np.isfinite(white) and white > 0):
        raise RenderInputError("white", "a scene white > 0", white)
    most = max(SAMPLE_COUNTS)
    reference = FrameSetting(MAX_LOBES, None, most if anisotropic else None)
    ref = np.asarray(probe(reference), dtype=np.float64)
    probes: list[tuple[FrameSetting, float]] = []

    def estimate(s: FrameSetting) -> float:
        err = frame_error(ref, probe(s), white, mask, percentile)
        probes.append((s, err))
        return err

    default = estimate(DEFAULT_SETTING)
    notes: list[str] = []

    def fits(err: float) -> bool:
        return err + margin_de <= tolerance_de and err <= default

    chosen, est = DEFAULT_SETTING, default
    for cand in candidates if margin_de <= tolerance_de else ():  # below the margin none can fit
        if cand == DEFAULT_SETTING:
            continue
        s = FrameSetting(cand.lobes, cand.environment_width, most if anisotropic else None)
        err = estimate(s)
        if fits(err):
            chosen, est = s, err
            break
    if anisotropic and chosen != DEFAULT_SETTING:
        for n in sorted(SAMPLE_COUNTS):
            if n >= most:
                break
            s = FrameSetting(chosen.lobes, chosen.environment_width, n)
            err = estimate(s)
            if fits(err):
                chosen, est = s, err
                break
    met = est + margin_de <= tolerance_de
    if not met:
        notes.append(
            f"No setting reaches ΔE {tolerance_de:g} with the margin: the default is drawn "
            f"(estimated {default:.2f} + {margin_de:.2f})."
        )
    return FrameLodChoice(
        chosen,
        est,
        default,
        float(margin_de),
        float(tolerance_de),
        met,
        reference,
        tuple(probes),
        int(probe_size),
        tuple(notes),
    )
