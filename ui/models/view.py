"""View state (environment, shape, exposure, orbit camera) and the cached per-pixel basis images.

The picture is linear in the paint's lobe weights (thesis eqs 2.5.1–2.5.3, as in
``station.render.numpy_renderer``)::

    radiance = w_D · D(N) + Σ_i (w_G,i + (N·V) w_DD,i) · C_i(R)

so for a fixed camera, shape and environment the per-pixel maps D(N) and C_i(R) (the *basis
images*) are computed once (:class:`BasisImages`, NumPy, using the core's ray caster and cube-map
lookups) and a paint edit only re-weights them: on the GPU in ``ui/shaders/composite.frag.glsl``,
or with :meth:`BasisImages.composite_linear` here. Nothing in this module imports Qt.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.render.camera import Camera
from station.render.cubemap import sample_cube
from station.render.envcache import PrefilterCache
from station.render.lobe_fit import fit_design
from station.render.numpy_renderer import BACKGROUND, gbuffer
from station.render.prefilter import PrefilteredBasis, prefilter_basis
from station.render.procedural import procedural_environment
from station.render.shapes import DEFAULT_CAMERAS, SHAPES, Scene
from station.render.tonemap import to_display
from station.render.weights import LobeWeights
from ui.models.events import EventGroup

ENVIRONMENTS = ("booth", "sky", "overcast")
ENV_WIDTH = 256
PREFILTER_MAX_SIZE = 64


class ViewInputError(InputError):
    """A view setting out of range (field name and accepted range)."""


@lru_cache(maxsize=256)
def paint_weights(design: FaceFlopTravelGloss) -> LobeWeights:
    """Lobe weights of *design* on the shipped basis (``station.render.lobe_fit.fit_design``), cached."""
    return fit_design(design)


def basis_exponents() -> tuple[float, ...]:
    """Phong exponents of the shipped lobe basis (those every fitted paint uses)."""
    from ui.models.document import DEFAULT_DESIGN

    return paint_weights(DEFAULT_DESIGN).exponents


@lru_cache(maxsize=4)
def environment_basis(env_name: str) -> PrefilteredBasis:
    """The procedural environment *env_name* prefiltered for the basis exponents (disk-cached)."""
    if env_name not in ENVIRONMENTS:
        raise ViewInputError("environment", " | ".join(ENVIRONMENTS), env_name)
    env = procedural_environment(env_name, ENV_WIDTH)
    return prefilter_basis(env, basis_exponents(), engine="numpy", cache=PrefilterCache(),
                           max_size=PREFILTER_MAX_SIZE)


@dataclass(frozen=True)
class ViewSettings:
    """What the 3D view shows: environment, shape, exposure (EV) and the orbit around the shape.

    ``yaw_deg``/``pitch_deg`` rotate the shape's default camera about the target (degrees),
    ``zoom`` divides the eye distance (1 = the default framing).
    """

    environment: str = "booth"
    shape: str = "sphere"
    exposure_ev: float = 0.0
    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    zoom: float = 1.0

    def __post_init__(self) -> None:
        if self.environment not in ENVIRONMENTS:
            raise ViewInputError("environment", " | ".join(ENVIRONMENTS), self.environment)
        if self.shape not in SHAPES:
            raise ViewInputError("shape", " | ".join(SHAPES), self.shape)
        if not (math.isfinite(self.exposure_ev) and -10.0 <= self.exposure_ev <= 10.0):
            raise ViewInputError("exposure_ev", "-10 <= EV <= 10", self.exposure_ev)
        if not (math.isfinite(self.pitch_deg) and -80.0 <= self.pitch_deg <= 80.0):
            raise ViewInputError("pitch_deg", "-80 <= pitch <= 80", self.pitch_deg)
        if not (math.isfinite(self.zoom) and 0.5 <= self.zoom <= 4.0):
            raise ViewInputError("zoom", "0.5 <= zoom <= 4", self.zoom)
        if not math.isfinite(self.yaw_deg):
            raise ViewInputError("yaw_deg", "a finite angle", self.yaw_deg)

    def camera(self) -> Camera:
        """The orbit camera: the shape's default camera turned by yaw/pitch and moved in by zoom."""
        base = DEFAULT_CAMERAS[self.shape]
        target = np.asarray(base.target, dtype=float)
        off = np.asarray(base.eye, dtype=float) - target
        dist = float(np.linalg.norm(off))
        pitch0 = math.degrees(math.asin(off[1] / dist))
        yaw0 = math.degrees(math.atan2(off[0], off[2]))
        pitch = math.radians(max(-85.0, min(85.0, pitch0 + self.pitch_deg)))
        yaw = math.radians(yaw0 + self.yaw_deg)
        d = dist / self.zoom
        eye = target + d * np.array([math.cos(pitch) * math.sin(yaw), math.sin(pitch),
                                     math.cos(pitch) * math.cos(yaw)])
        return Camera(tuple(map(float, eye)), base.target, base.up, base.fov_deg)

    def scene(self) -> Scene:
        """The core scene (shape + orbit camera)."""
        return Scene(self.shape, camera=self.camera())

    def replace(self, **kw: object) -> ViewSettings:
        """A copy with fields replaced (validated)."""
        return replace(self, **kw)  # type: ignore[arg-type]


@dataclass(frozen=True, eq=False)
class BasisImages:
    """Per-pixel maps of one view (row 0 at the top): D(N) (H, W, 3), C_i(R) (m, H, W, 3), N·V and paint id.

    ``paint`` is −1 off the object, 0 or 1 on the two paint halves of the shape.
    """

    exponents: tuple[float, ...]
    diffuse: np.ndarray = field(repr=False)
    lobes: np.ndarray = field(repr=False)
    n_dot_v: np.ndarray = field(repr=False)
    paint: np.ndarray = field(repr=False)

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return int(self.paint.shape[1]), int(self.paint.shape[0])

    @classmethod
    def compute(cls, settings: ViewSettings, width: int, height: int) -> BasisImages:
        """Ray-cast the view and look up every prefiltered map once (the slow part, done per camera)."""
        basis = environment_basis(settings.environment)
        g = gbuffer(settings.scene(), width, height)
        m = g.mask
        diffuse = np.zeros((height, width, 3), np.float32)
        lobes = np.zeros((len(basis.cubes), height, width, 3), np.float32)
        if m.any():
            diffuse[m] = sample_cube(basis.diffuse, g.normal[m])
            r = g.reflect[m]
            for i, cube in enumerate(basis.cubes):
                lobes[i][m] = sample_cube(cube, r)
        return cls(basis.exponents, diffuse, lobes, g.n_dot_v.astype(np.float32), g.paint.copy())

    def composite_linear(self, paints: tuple[LobeWeights, LobeWeights]) -> np.ndarray:
        """Linear sRGB radiance (H, W, 3) float32 of two paints (module equation)."""
        out = np.full((*self.paint.shape, 3), BACKGROUND, np.float32)
        for k, w in enumerate(paints):
            m = self.paint == k
            if not m.any():
                continue
            w_d, w_dd, w_g = w.map_weights()
            acc = w_d * self.diffuse[m]
            ndv = self.n_dot_v[m][:, None]
            for i in range(len(self.exponents)):
                acc = acc + (w_g[i] + ndv * w_dd[i]) * self.lobes[i][m]
            out[m] = acc
        return out

    def composite_display(self, paints: tuple[LobeWeights, LobeWeights], exposure_ev: float) -> np.ndarray:
        """8-bit sRGB (H, W, 3) of :meth:`composite_linear` (``station.render.tonemap.to_display``)."""
        return to_display(self.composite_linear(paints), exposure_ev)


class ViewModel:
    """Observable :class:`ViewSettings` plus the paints shown (Qt-free).

    Events: ``settings(settings)`` on any setting change; ``paints(pair)`` when a shown design changes.
    """

    def __init__(self, settings: ViewSettings | None = None) -> None:
        self._settings = settings or ViewSettings()
        self._designs: tuple[FaceFlopTravelGloss, FaceFlopTravelGloss] | None = None
        self.events = EventGroup("settings", "paints")

    @property
    def settings(self) -> ViewSettings:
        """Current settings."""
        return self._settings

    def update(self, **kw: object) -> None:
        """Change settings (validated by :class:`ViewSettings`; raises ViewInputError)."""
        new = self._settings.replace(**kw)
        if new != self._settings:
            self._settings = new
            self.events.settings.emit(new)

    def show(self, design: FaceFlopTravelGloss, other: FaceFlopTravelGloss | None = None) -> None:
        """Show *design* on both halves, or *design* | *other* side by side."""
        pair = (design, other if other is not None else design)
        if pair != self._designs:
            self._designs = pair
            self.events.paints.emit(pair)

    @property
    def designs(self) -> tuple[FaceFlopTravelGloss, FaceFlopTravelGloss] | None:
        """The two designs shown (left, right), or None before the first :meth:`show`."""
        return self._designs

    def weights(self) -> tuple[LobeWeights, LobeWeights] | None:
        """Lobe weights of the two shown designs."""
        if self._designs is None:
            return None
        return paint_weights(self._designs[0]), paint_weights(self._designs[1])
