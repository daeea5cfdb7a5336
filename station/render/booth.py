"""The virtual light booth: a standard and a trial paint as the two halves of a part, under an illuminant.

Each paint is given by its reflectance spectra per aspecular geometry (400–700 nm, 10 nm). Under an
illuminant and observer:

* **Paint colour (the adapted observer).** The spectra give Lab under the illuminant relative to its own
  white (ASTM E308, ``station.model.spectra``); their CAT16 corresponding colour under D65 (full
  adaptation, ``station.model.booth.display_design_under``), as the product's D65 Lab per geometry, is
  fitted to a face/flop/travel/gloss design (thesis §3.3,
  ``station.model.fit_fftg``) and its lobe weights (thesis eqs 2.4.1–2.4.2). A white paint therefore looks
  white under every illuminant, and two paints that match under D65 but not under A (metamerism) look
  alike in the D65 picture and different in the A one, as a viewer adapted to the booth light sees them.
* **Light colour (what adaptation leaves).** A viewer of the picture sits at a D65 display, not in the
  booth, and adapts only partly to the booth light. The whole frame (paints, walls, floor) is multiplied
  by the illuminant's white seen with the CIECAM16 degree of adaptation D of a viewer at a display
  (L_A = ``DISPLAY_ADAPTING_CD_M2``, average surround: D ≈ 0.86; two-step CAT16), normalised to luminance
  1 (:func:`light_tint`). D65 gives (1, 1, 1); A gives a warm light, F11 a slightly warm one. For neutral
  surfaces (walls, floor) this is the partial CAT16 exactly; for the paints it is its per-channel
  approximation in linear sRGB. The tint multiplies both halves alike, so it never creates or hides a
  difference between them: the table beside the picture (CIELAB under the illuminant's own white,
  CIEDE2000, the metamerism index) is the measure, the picture the impression.

The booth is ``station.render.procedural.light_booth`` (neutral grey walls and floor, two overhead
diffusers) on a stage (backdrop and ground). For a fixed shape and view the image is linear in the lobe
weights (docs/design.md §4), so :class:`BoothRenderer` caches the basis images of each shape
(``station.render.basis_images``; the car's come from the GL renderer, one unit-weight render per image)
and an illuminant switch costs two design fits and one weighted sum (bench/booth.py).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import NDArray

from station.model.booth import BOOTH_SHAPES, check_booth_shape
from station.model.colorimetry import OBSERVER_10, REC709_LUMINANCE
from station.model.errors import ModelInputError
from station.render.errors import RenderInputError

__all__ = [
    "BOOTH_SHAPES",
    "BoothFrame",
    "BoothPaint",
    "BoothRenderer",
    "adapted_lab",
    "booth_design",
    "booth_strip",
    "light_tint",
    "paint_from_reading",
    "render_booth_file",
    "render_booth_png",
]

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss
    from station.model.illuminants import Illuminant
    from station.render.basis_images import BasisImages
    from station.render.prefilter import PrefilteredBasis
    from station.render.weights import LobeWeights

#: Default picture size (pixels, square).
BOOTH_SIZE = 384
#: Largest picture side (pixels).
BOOTH_MAX_SIZE = 2048
#: Width of the booth environment (equirect pixels) before prefiltering.
BOOTH_ENV_WIDTH = 256
#: Adapting luminance of a viewer at the display, cd/m² (20 % of a 100 cd/m² white).
DISPLAY_ADAPTING_CD_M2 = 20.0
#: Exposure of the booth pictures (EV): the booth's irradiance/π is 1, a bright silver face is ~2.
BOOTH_EXPOSURE_EV = 0.0


@dataclass(frozen=True)
class BoothPaint:
    """One paint in the booth: reflectance spectra per aspecular geometry and its gloss.

    ``aspecular_deg``: the geometries' aspecular angles, degrees (45° illumination); ``spectra``: (n, 31)
    reflectance factors at 400–700 nm, 10 nm; ``gloss_gu``: specular gloss at 60°, GU, or None; ``name``.
    """

    aspecular_deg: tuple[float, ...]
    spectra: NDArray[np.float64] = field(repr=False)
    gloss_gu: float | None = None
    name: str = ""

    def __post_init__(self) -> None:
        from station.model.spectra import WAVELENGTHS

        angles = tuple(float(a) for a in self.aspecular_deg)
        sp = np.asarray(self.spectra, dtype=float)
        field_name = f"{self.name or 'paint'}.spectra"
        if sp.shape != (len(angles), WAVELENGTHS.size) or not np.all(np.isfinite(sp)):
            raise RenderInputError(
                field_name,
                f"{len(angles)} finite spectra of {WAVELENGTHS.size} values (400–700 nm, 10 nm)",
                sp.shape,
            )
        if sum(1 for a in angles if a > 0) < 3:
            raise RenderInputError(
                f"{self.name or 'paint'}.geometries", "at least 3 positive aspecular angles", angles
            )
        object.__setattr__(self, "aspecular_deg", angles)
        object.__setattr__(self, "spectra", sp)


def adapted_lab(
    spectra: NDArray[np.float64], illuminant: str | Illuminant = "D65", observer: str = OBSERVER_10
) -> NDArray[np.float64]:
    """The product's Lab (D65) of reflectance *spectra* (..., 31) seen under *illuminant* by a viewer fully
    adapted to it: Lab under the illuminant's own white (``station.model.spectra.reflectance_to_lab``),
    its CAT16 corresponding colour under D65 (``station.model.booth.display_equivalent_lab``). Identity
    under D65 (module doc)."""
    from station.model.booth import display_equivalent_lab
    from station.model.spectra import reflectance_to_lab

    lab = reflectance_to_lab(spectra, illuminant, observer)
    return np.asarray(display_equivalent_lab(lab, illuminant, observer), dtype=float)


def degree_of_adaptation(adapting_cd_m2: float = DISPLAY_ADAPTING_CD_M2, f: float = 1.0) -> float:
    """CIECAM16 degree of adaptation D = F (1 − (1/3.6) exp((−L_A − 42)/92)) (CIE 248:2022), in [0, 1]."""
    return float(np.clip(f * (1.0 - math.exp((-adapting_cd_m2 - 42.0) / 92.0) / 3.6), 0.0, 1.0))


def light_tint(
    illuminant: str | Illuminant = "D65", observer: str = OBSERVER_10, degree: float | None = None
) -> NDArray[np.float64]:
    """(3,) linear sRGB multiplier of the booth light: the illuminant's white seen with degree of
    adaptation *degree* (default :func:`degree_of_adaptation`; ``station.model.booth.lab_to_linear_srgb_under``,
    CAT16 two-step), divided by D65's (the display's light) and scaled to luminance 1 (module doc). D65 gives (1, 1, 1)."""
    from station.model.booth import lab_to_linear_srgb_under

    d = degree_of_adaptation() if degree is None else degree
    if isinstance(d, bool) or not isinstance(d, (int, float)) or not 0.0 <= d <= 1.0:
        raise RenderInputError("degree", "0 <= degree <= 1", degree)
    white = np.array([100.0, 0.0, 0.0])
    rgb = np.maximum(lab_to_linear_srgb_under(white, illuminant, observer, float(d)), 0.0)
    # Relative to D65 seen the same way: D65 is the display's own light (its 10° white differs from the
    # display's 2° one by a hair that partial adaptation would otherwise leave as a tint).
    rgb = rgb / np.maximum(lab_to_linear_srgb_under(white, "D65", observer, float(d)), 1e-12)
    return np.asarray(rgb / float(rgb @ REC709_LUMINANCE), dtype=float)


def booth_design(
    paint: BoothPaint, illuminant: str | Illuminant = "D65", observer: str = OBSERVER_10
) -> FaceFlopTravelGloss:
    """The design to render for *paint* under *illuminant*: ``station.model.booth.display_design_under``
    of its positive aspecular geometries (the adapted colour, thesis eqs 3.3.1–3.3.10)."""
    from station.model.booth import display_design_under

    keep = sorted((a, i) for i, a in enumerate(paint.aspecular_deg) if a > 0)
    angles = [a for a, _ in keep]
    spectra = paint.spectra[[i for _, i in keep]]
    with warnings.catch_warnings():  # a fit's residual warning: the picture is drawn all the same
        warnings.simplefilter("ignore")
        return display_design_under(spectra, angles, illuminant, observer, paint.gloss_gu).design


def _check_shape(shape: str) -> str:
    """*shape* when it is one of the model's BOOTH_SHAPES (panels, seam, car), else RenderInputError."""
    try:
        return check_booth_shape(shape)
    except ModelInputError as exc:
        raise RenderInputError(exc.field, exc.accepted, exc.got) from None


def _check_size(size: int) -> int:
    if isinstance(size, bool) or not isinstance(size, int) or not 16 <= size <= BOOTH_MAX_SIZE:
        raise RenderInputError("size", f"an integer 16 <= size <= {BOOTH_MAX_SIZE}", size)
    return size


def _unit_weights(exponents: tuple[float, ...], kind: str, i: int) -> LobeWeights:
    """Weights whose map weight (LobeWeights.map_weights) is 1 for one image of the GL probe layout."""
    from station.render.weights import LobeWeights

    m = len(exponents)
    k_d, k_a, k_dd, k_g = np.zeros(3), np.zeros(3), np.zeros((m, 3)), np.zeros(m)
    if kind == "D":
        k_d[:] = 1.0 / np.pi
    elif kind == "A":
        k_a[:] = 1.0 / np.pi
    elif kind == "Dg":
        k_dd[i] = (exponents[i] + 1.0) / (2.0 * np.pi)
    elif kind == "Gh":
        k_g[i] = (exponents[i] + 1.0) / (2.0 * np.pi)
    return LobeWeights(exponents, k_d, k_dd, k_g, k_a)


def mesh_basis_images(basis: PrefilteredBasis, size: int, gl_ctx: object = None) -> BasisImages:
    """Basis images of the built-in car body on the booth stage, probed with the GL renderer.

    One render per image with unit weights on both halves (layout D, A, then (Gh, i), (Dg, i) per lobe:
    every lobe's directionally diffuse image holds its N·V factor, so the cached N·V is unused), minus the
    render with zero weights (the stage behind); the halves' pixels from a diffuse probe on each. The
    fall-off image A is the unit-K_A render minus the unit-K_D one (``weights`` module doc). *gl_ctx*: a
    moderngl context to draw on (default: a headless one of its own)."""
    from station.render.basis_images import BasisImages
    from station.render.gl_renderer import GLRenderer
    from station.render.scene_image import builtin_mesh
    from station.render.stage import Stage

    mesh = builtin_mesh("car")
    e = basis.exponents
    layout: list[tuple[str, int]] = [("D", -1), ("A", -1)]
    for i in range(len(e)):
        layout += [("Gh", i), ("Dg", i)]
    zero = _unit_weights(e, "", -1)
    stage = Stage()
    with GLRenderer(basis, size, size, ctx=gl_ctx) as gl:

        def shot(pair: list[LobeWeights]) -> NDArray[np.float32]:
            return np.asarray(gl.render_mesh(mesh, pair, stage=stage, linear=True), np.float32).reshape(-1, 3)

        back = shot([zero, zero])
        d = _unit_weights(e, "D", -1)
        left = np.flatnonzero(np.abs(shot([d, zero]) - back).max(axis=1) > 1e-6)
        right = np.flatnonzero(np.abs(shot([zero, d]) - back).max(axis=1) > 1e-6)
        pixels = np.concatenate([left, right])
        probes = {kind_i: shot([_unit_weights(e, *kind_i)] * 2) for kind_i in layout}
    images = np.empty((3, len(layout), pixels.size), np.float32)
    for j, kind_i in enumerate(layout):
        img = probes[kind_i] - (probes[("D", -1)] if kind_i[0] == "A" else back)
        images[:, j] = img[pixels].T
    return BasisImages(
        basis,
        size,
        size,
        pixels,
        int(left.size),
        np.ascontiguousarray(images),
        np.zeros(pixels.size, np.float32),
        tuple(layout),
        background=back,
    )


#: Longest wait for the process that draws the car's basis images (seconds).
ISOLATED_TIMEOUT_S = 300.0


def mesh_basis_images_isolated(basis: PrefilteredBasis, size: int) -> BasisImages:
    """:func:`mesh_basis_images` run by a Python process of its own (``python -m station.render.booth``,
    the basis in and the images out as pickles over its stdin / stdout), so its headless EGL context
    never shares a process with the caller's GL (a Qt viewer: Mesa cannot make a Qt GLX context current
    in a process that has used EGL, docs/adr/0003). Costs the child's start (about a second) per view;
    RenderError with the child's last error line when it fails."""
    import pickle
    import subprocess
    import sys

    from station.render.errors import RenderError

    try:
        done = subprocess.run(  # this interpreter running this module
            [sys.executable, "-m", "station.render.booth"],
            input=pickle.dumps((basis, int(size))),
            capture_output=True,
            timeout=ISOLATED_TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired as exc:
        raise RenderError(f"car basis images: no answer in {ISOLATED_TIMEOUT_S:g} s") from exc
    if done.returncode != 0:
        lines = done.stderr.decode("utf-8", "replace").strip().splitlines() or ["no message"]
        raise RenderError(f"car basis images: the drawing process failed: {lines[-1]}")
    images: BasisImages = pickle.loads(done.stdout)  # our own child's answer
    return images


def _serve_mesh_basis_images() -> None:
    """The child of :func:`mesh_basis_images_isolated`: (basis, size) pickled on stdin → images on stdout."""
    import pickle
    import sys

    basis, size = pickle.loads(sys.stdin.buffer.read())  # from our own parent
    sys.stdout.buffer.write(pickle.dumps(mesh_basis_images(basis, size), protocol=pickle.HIGHEST_PROTOCOL))
    sys.stdout.buffer.flush()


@dataclass(frozen=True)
class BoothFrame:
    """A booth picture: ``image`` (H, W, 3) uint8 sRGB, the ``designs`` (standard, trial) it shows, the
    light ``tint`` (3,) and the ``seconds`` the frame took (fits and weighted sum, cached views)."""

    image: NDArray[np.uint8]
    designs: tuple[FaceFlopTravelGloss, FaceFlopTravelGloss]
    tint: NDArray[np.float64]
    seconds: float


class BoothRenderer:
    """Renders booth pictures, keeping the prefiltered booth and each shape's basis images (module doc).

            ``size``: picture side in pixels; ``gl_ctx``: a moderngl context for the car's basis images (default:
            a headless one made when needed); ``basis``: the prefiltered booth of another renderer to share
        (default: built on first use); ``isolate_gl``: build the car's images in a process of its own
    (:func:`mesh_basis_images_isolated`, for a caller with GL of its own, the viewer). One renderer per caller (a viewer screen, a CLI run); not shared
            between threads.
    """

    def __init__(
        self,
        size: int = BOOTH_SIZE,
        gl_ctx: object = None,
        basis: PrefilteredBasis | None = None,
        isolate_gl: bool = False,
    ) -> None:
        self.size = _check_size(size)
        self._gl_ctx = gl_ctx
        self._isolate_gl = bool(isolate_gl)
        self._basis = basis
        self._views: dict[str, BasisImages] = {}

    @property
    def basis(self) -> PrefilteredBasis:
        """The booth environment prefiltered for the default lobe basis (built on first use)."""
        if self._basis is None:
            from station.render.envcache import PrefilterCache
            from station.render.lobes import default_basis
            from station.render.prefilter import prefilter_basis
            from station.render.procedural import light_booth
            from station.render.scene_image import PREFILTER_SIZE

            self._basis = prefilter_basis(
                light_booth(BOOTH_ENV_WIDTH),
                default_basis().exponents,
                engine="numpy",
                cache=PrefilterCache(),
                max_size=PREFILTER_SIZE,
            )
        return self._basis

    def cached(self, shape: str) -> bool:
        """Whether *shape*'s basis images are built (a switch then costs fits and one weighted sum)."""
        return _check_shape(shape) in self._views

    def view(self, shape: str) -> BasisImages:
        """Basis images of *shape* on the booth stage (built on first use: NumPy ray casting for the
        panels and the seam, the GL renderer for the car, GLUnavailableError without an OpenGL stack)."""
        if _check_shape(shape) not in self._views:
            if shape == "car":
                self._views[shape] = (
                    mesh_basis_images_isolated(self.basis, self.size)
                    if self._isolate_gl
                    else mesh_basis_images(self.basis, self.size, self._gl_ctx)
                )
            else:
                from station.render.basis_images import build_basis_images
                from station.render.shapes import Scene
                from station.render.stage import Stage

                scene = Scene(shape, stage=Stage())
                self._views[shape] = build_basis_images(scene, self.basis, self.size, self.size)
        return self._views[shape]

    def frame(
        self,
        standard: BoothPaint,
        trial: BoothPaint,
        illuminant: str | Illuminant = "D65",
        observer: str = OBSERVER_10,
        shape: str = "panels",
    ) -> BoothFrame:
        """The booth picture of *standard* (left half: left panel, fender, car's rear) and *trial* (right
        half: right panel, bumper, car's front) under *illuminant* for *observer* (module doc)."""
        import time

        from station.render import lobe_fit, tonemap
        from station.render.lobes import default_basis

        images = self.view(shape)
        t0 = time.perf_counter()
        designs = (booth_design(standard, illuminant, observer), booth_design(trial, illuminant, observer))
        lobes = default_basis()
        paints = [lobe_fit.fit_design(d, lobes) for d in designs]
        tint = light_tint(illuminant, observer)
        linear = images.linear_image(paints) * tint.astype(np.float32)
        image = tonemap.to_display(linear, BOOTH_EXPOSURE_EV)
        return BoothFrame(image, designs, tint, time.perf_counter() - t0)


def write_png(image: NDArray[np.uint8], out_path: str | Path) -> Path:
    """Write an (H, W, 3) uint8 picture as PNG (Pillow); RenderInputError naming ``out`` when it fails."""
    from PIL import Image

    path = Path(out_path)
    try:
        Image.fromarray(np.ascontiguousarray(image)).save(path, format="PNG", optimize=True)
    except (OSError, ValueError) as exc:
        raise RenderInputError("out", "a writable .png path", str(path), detail=type(exc).__name__) from exc
    return path


def render_booth_png(
    standard: BoothPaint,
    sample: BoothPaint,
    illuminant: str | Illuminant = "D65",
    observer: str = OBSERVER_10,
    shape: str = "panels",
    out_path: str | Path = "booth.png",
    size: int = BOOTH_SIZE,
    renderer: BoothRenderer | None = None,
) -> Path:
    """Render the booth (standard left, *sample* right) under *illuminant* and write it to *out_path*."""
    r = renderer if renderer is not None else BoothRenderer(size)
    return write_png(r.frame(standard, sample, illuminant, observer, shape).image, out_path)


def booth_strip(
    standard: BoothPaint,
    sample: BoothPaint,
    illuminants: Sequence[str | Illuminant],
    observer: str = OBSERVER_10,
    shape: str = "panels",
    size: int = BOOTH_SIZE,
    renderer: BoothRenderer | None = None,
) -> NDArray[np.uint8]:
    """The booth under each of *illuminants*, side by side (H, W·n, 3) uint8 (one cached view)."""
    if not illuminants:
        raise RenderInputError("illuminants", "at least one illuminant", list(illuminants))
    r = renderer if renderer is not None else BoothRenderer(size)
    return np.concatenate(
        [r.frame(standard, sample, ill, observer, shape).image for ill in illuminants], axis=1
    )


class SpectralReading(Protocol):
    """What :func:`paint_from_reading` reads of a reading (``station.qc.readings.Reading`` has it)."""

    @property
    def aspecular_deg(self) -> tuple[float, ...]: ...
    @property
    def spectra(self) -> tuple[tuple[float, ...], ...] | None: ...
    @property
    def wavelengths_nm(self) -> tuple[float, ...] | None: ...


def paint_from_reading(reading: SpectralReading, role: str, gloss_gu: float | None = None) -> BoothPaint:
    """A :class:`BoothPaint` of a reading's spectra at the product's wavelengths (400–700 nm, 10 nm).

    RenderInputError naming ``<role>.spectra`` when the reading has no spectra or misses a band."""
    from station.model.spectra import WAVELENGTHS

    if reading.spectra is None or reading.wavelengths_nm is None:
        raise RenderInputError(f"{role}.spectra", "a reading with spectra", "no spectra")
    wl = [float(w) for w in reading.wavelengths_nm]
    missing = [float(w) for w in WAVELENGTHS if float(w) not in wl]
    if missing:
        raise RenderInputError(
            f"{role}.spectra", "every band of 400–700 nm at 10 nm", f"missing {missing[:3]}"
        )
    cols = [wl.index(float(w)) for w in WAVELENGTHS]
    return BoothPaint(reading.aspecular_deg, np.asarray(reading.spectra, float)[:, cols], gloss_gu, role)


def _caption(image: NDArray[np.uint8], text: str) -> NDArray[np.uint8]:
    """*image* with a strip of *text* below it (Pillow's default font)."""
    from PIL import Image, ImageDraw

    h, w = image.shape[:2]
    bar = max(14, h // 16)
    canvas = Image.new("RGB", (w, h + bar), (32, 32, 32))
    canvas.paste(Image.fromarray(np.ascontiguousarray(image)), (0, 0))
    ImageDraw.Draw(canvas).text((4, h + (bar - 11) // 2), text, fill=(235, 235, 235))
    return np.asarray(canvas)


def render_booth_file(
    *,
    comparison: object,
    standard: SpectralReading,
    sample: SpectralReading,
    illuminants: Sequence[str | Illuminant],
    observer: str,
    shape: str,
    out: Path,
    size: int = BOOTH_SIZE,
) -> Path:
    """``station booth --out``: the booth under each illuminant side by side, each tile captioned with the
    illuminant and, when *comparison* (``station.qc.booth.BoothComparison``) is given, its mean ΔE00."""
    std, smp = paint_from_reading(standard, "standard"), paint_from_reading(sample, "sample")
    if not illuminants:
        raise RenderInputError("illuminants", "at least one illuminant", [])
    r = BoothRenderer(size)
    tiles = []
    for ill in illuminants:
        name = getattr(ill, "name", ill)
        text = f"{name}"
        under = getattr(comparison, "under", None)
        if under is not None:
            text += f"   mean dE00 {under(name).mean_de:.2f}"
        tiles.append(_caption(r.frame(std, smp, ill, observer, shape).image, text))
    return write_png(np.concatenate(tiles, axis=1), out)


if __name__ == "__main__":
    _serve_mesh_basis_images()
