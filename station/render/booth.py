"""The virtual light booth: a standard and a trial paint as the two halves of a part, under an illuminant.

Each paint is given by its reflectance spectra per aspecular geometry (400–700 nm, 10 nm). Under an
illuminant and observer:

* **Paint colour (the adapted observer).** The spectra give XYZ under the illuminant (ASTM E308,
  ``station.model.spectra``); CAT16 (colour-science, full adaptation) maps them to the D65 display white,
  and their CIELAB (D65) per geometry is fitted to a face/flop/travel/gloss design (thesis §3.3,
  ``station.model.fit_fftg``) and its lobe weights (thesis eqs 2.4.1–2.4.2). A white paint therefore looks
  white under every illuminant, and two paints that match under D65 but not under A (metamerism) look
  alike in the D65 picture and different in the A one, as a viewer adapted to the booth light sees them.
* **Light colour (what adaptation leaves).** A viewer of the picture sits at a D65 display, not in the
  booth, and adapts only partly to the booth light. The whole frame (paints, walls, floor) is multiplied
  by the illuminant's white after CAT16 with the CIECAM16 degree of adaptation D for a display
  (L_A = ``DISPLAY_ADAPTING_CD_M2``, average surround: D ≈ 0.86), normalised to luminance 1
  (:func:`light_tint`). D65 gives (1, 1, 1); A gives a warm and F11 a slightly green-yellow light. The tint
  multiplies both halves alike, so it never creates or hides a difference between them.

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
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from station.model.colorimetry import OBSERVER_10
from station.render.errors import RenderInputError

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss
    from station.render.basis_images import BasisImages
    from station.render.prefilter import PrefilteredBasis
    from station.render.weights import LobeWeights

#: Parts the booth shows: two flat panels side by side, a fender-over-bumper seam, the car body.
BOOTH_SHAPES = ("panels", "seam", "car")
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
#: Luminance of linear sRGB (ITU-R BT.709 primaries, D65): Y = RGB · these.
_SRGB_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


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
                field_name, f"{len(angles)} finite spectra of {WAVELENGTHS.size} values (400–700 nm, 10 nm)", sp.shape
            )
        if sum(1 for a in angles if a > 0) < 3:
            raise RenderInputError(
                f"{self.name or 'paint'}.geometries", "at least 3 positive aspecular angles", angles
            )
        object.__setattr__(self, "aspecular_deg", angles)
        object.__setattr__(self, "spectra", sp)


def adapted_lab(
    spectra: NDArray[np.float64], illuminant: str = "D65", observer: str = OBSERVER_10
) -> NDArray[np.float64]:
    """CIELAB (D65 white) of reflectance *spectra* (..., 31) seen under *illuminant* by a viewer fully
    adapted to it: XYZ under the illuminant (ASTM E308), CAT16 to D65 (colour-science), Lab (module doc)."""
    import colour

    from station.model.spectra import reflectance_to_xyz, whitepoint_xyz

    xyz = reflectance_to_xyz(spectra, illuminant, observer)
    white = whitepoint_xyz(illuminant, observer)
    d65 = whitepoint_xyz("D65", observer)
    adapted = colour.adaptation.chromatic_adaptation_VonKries(xyz, white, d65, transform="CAT16")
    return np.asarray(colour.XYZ_to_Lab(adapted, colour.XYZ_to_xy(d65)), dtype=float)


def degree_of_adaptation(adapting_cd_m2: float = DISPLAY_ADAPTING_CD_M2, f: float = 1.0) -> float:
    """CIECAM16 degree of adaptation D = F (1 − (1/3.6) exp((−L_A − 42)/92)) (CIE 248:2022), in [0, 1]."""
    return float(np.clip(f * (1.0 - math.exp((-adapting_cd_m2 - 42.0) / 92.0) / 3.6), 0.0, 1.0))


def light_tint(
    illuminant: str = "D65", observer: str = OBSERVER_10, degree: float | None = None
) -> NDArray[np.float64]:
    """(3,) linear sRGB multiplier of the booth light: the illuminant's white after CAT16 to D65 with
    degree of adaptation *degree* (default :func:`degree_of_adaptation`), luminance 1 (module doc)."""
    import colour

    from station.model.spectra import whitepoint_xyz

    d = degree_of_adaptation() if degree is None else float(degree)
    if not 0.0 <= d <= 1.0:
        raise RenderInputError("degree", "0 <= degree <= 1", degree)
    white = whitepoint_xyz(illuminant, observer)
    d65 = whitepoint_xyz("D65", observer)
    m = np.asarray(colour.adaptation.CAT_CAT16)
    lms = d * (m @ d65) + (1.0 - d) * (m @ white) * (d65[1] / white[1])
    xyz = np.linalg.solve(m, lms)
    rgb = np.asarray(colour.XYZ_to_RGB(xyz, "sRGB", illuminant=colour.XYZ_to_xy(d65)), dtype=float)
    rgb = np.maximum(rgb, 0.0)
    return rgb / float(rgb @ _SRGB_LUMINANCE)


def booth_design(
    paint: BoothPaint, illuminant: str = "D65", observer: str = OBSERVER_10
) -> FaceFlopTravelGloss:
    """The face/flop/travel/gloss design of *paint* under *illuminant* (adapted Lab of its positive
    aspecular geometries, thesis eqs 3.3.1–3.3.10)."""
    from station.model import AspecularMeasurements, fit_fftg

    keep = sorted((a, i) for i, a in enumerate(paint.aspecular_deg) if a > 0)
    angles = tuple(a for a, _ in keep)
    lab = adapted_lab(paint.spectra[[i for _, i in keep]], illuminant, observer)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_fftg(AspecularMeasurements(angles, lab, paint.gloss_gu)).design


def _check_shape(shape: str) -> str:
    if shape not in BOOTH_SHAPES:
        raise RenderInputError("shape", " | ".join(BOOTH_SHAPES), shape)
    return shape


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


def mesh_basis_images(basis: PrefilteredBasis, size: int) -> BasisImages:
    """Basis images of the built-in car body on the booth stage, probed with the GL renderer.

    One render per image with unit weights on both halves (layout D, A, then (Gh, i), (Dg, i) per lobe:
    every lobe's directionally diffuse image holds its N·V factor, so the cached N·V is unused), minus the
    render with zero weights (the stage behind); the halves' pixels from a diffuse probe on each. The
    fall-off image A is the unit-K_A render minus the unit-K_D one (``weights`` module doc)."""
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
    with GLRenderer(basis, size, size) as gl:

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

    ``size``: picture side in pixels. One renderer per caller (a viewer screen, a CLI run); not shared
    between threads.
    """

    def __init__(self, size: int = BOOTH_SIZE) -> None:
        self.size = _check_size(size)
        self._basis: PrefilteredBasis | None = None
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
                self._views[shape] = mesh_basis_images(self.basis, self.size)
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
        illuminant: str = "D65",
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
    illuminant: str = "D65",
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
    illuminants: Sequence[str],
    observer: str = OBSERVER_10,
    shape: str = "panels",
    size: int = BOOTH_SIZE,
    renderer: BoothRenderer | None = None,
) -> NDArray[np.uint8]:
    """The booth under each of *illuminants*, side by side (H, W·n, 3) uint8 (one cached view)."""
    if not illuminants:
        raise RenderInputError("illuminants", "at least one illuminant", list(illuminants))
    r = renderer if renderer is not None else BoothRenderer(size)
    return np.concatenate([r.frame(standard, sample, ill, observer, shape).image for ill in illuminants], axis=1)
