"""View state (environment, shape, exposure, orbit camera) and the cached per-pixel basis images.

The picture is linear in the paint's lobe weights (thesis eqs 2.5.1–2.5.3, as in
``station.render.numpy_renderer``), so for a fixed camera, shape and environment the per-pixel
*basis images* are computed once by the core (:mod:`station.render.basis_images`) and a paint edit only
re-weights them: on the GPU in ``ui/shaders/composite.frag.glsl``, or with the core's NumPy path
(:meth:`BasisImages.composite_linear`). Nothing in this module imports Qt.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.model.flakes import FLAKE_RANGES, FlakeLayer
from station.model.gloss import ClearCoat
from station.render.basis_images import BasisImages as CoreBasisImages
from station.render.basis_images import build_basis_images
from station.render.camera import Camera
from station.render.envcache import PrefilterCache
from station.render.environment import Environment, load_environment
from station.render.lobe_fit import fit_design
from station.render.meshes import MESH_CAMERA, MESH_SUFFIXES, Mesh
from station.render.prefilter import PrefilteredBasis, prefilter_basis
from station.render.procedural import procedural_environment
from station.render.scene_image import BUILTIN_MESHES, builtin_mesh
from station.render.shapes import DEFAULT_CAMERAS, SHAPES, Scene
from station.render.tonemap import to_display
from station.render.weights import LobeWeights
from ui.models.events import EventGroup

ENVIRONMENTS = ("booth", "sky", "overcast")
#: File types the viewer loads as environments (``station.render.environment.load_environment``).
ENVIRONMENT_SUFFIXES = (".hdr", ".exr")
ENV_WIDTH = 256
PREFILTER_MAX_SIZE = 64
PREVIEW_PREFILTER_SIZE = 16  # cube faces of the first-frame prefilter (brute quadrature, ~0.1 s)
#: Anti-aliasing of the view's final frames, samples per pixel (``station.render.gl_targets.AA_SAMPLES``):
#: the basis images' edge pixels are supersampled (``build_basis_images(aa=...)``, a small share of the
#: worker's time), and a GL frame the view stays on (flakes, own models) is redrawn supersampled once the
#: view is still. Frames drawn while the view moves are shaded once per pixel.
VIEW_AA = 4


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


_READY: set[tuple[str, int]] = set()


def is_environment_file(name: str) -> bool:
    """Whether *name* names an environment file (a path ending in .hdr or .exr) rather than a built-in."""
    return Path(name).suffix.lower() in ENVIRONMENT_SUFFIXES


def check_environment(name: str) -> None:
    """Accept a built-in environment name or the path of an existing .hdr/.exr file (ViewInputError)."""
    if name in ENVIRONMENTS:
        return
    if not isinstance(name, str) or not is_environment_file(name) or not Path(name).is_file():
        raise ViewInputError(
            "environment", " | ".join(ENVIRONMENTS) + " | the path of an existing .hdr/.exr file", name
        )


@lru_cache(maxsize=8)
def _file_environment(path: str, _mtime_ns: int) -> Environment:
    """The environment file *path*, downsampled to ENV_WIDTH; the modification time only keys the cache
    (a file rewritten in place is read again)."""
    env = load_environment(path)
    return env.downsampled(ENV_WIDTH) if env.equirect.shape[1] > ENV_WIDTH else env


def load_environment_file(path: str | Path) -> Environment:
    """The environment in an .hdr/.exr file at the viewer's working width (ENV_WIDTH), cached per file
    version; EnvironmentFileError (names the file) for a file that is not a usable HDR image."""
    p = Path(path)
    check_environment(str(p))
    return _file_environment(str(p), p.stat().st_mtime_ns)


def environment_basis(env_name: str, max_size: int = PREFILTER_MAX_SIZE) -> PrefilteredBasis:
    """The environment *env_name* (built-in name or .hdr/.exr path) prefiltered for the basis exponents
    (disk-cached).

    *max_size* caps the cube face size: PREFILTER_MAX_SIZE for the full-quality view,
    PREVIEW_PREFILTER_SIZE for the first frame of a cold cache (same environment and lobes, coarser
    maps of the narrow lobes; ~0.1 s instead of ~3 s).
    """
    check_environment(env_name)
    basis = _environment_basis(env_name, int(max_size))
    _READY.add((env_name, int(max_size)))
    return basis


def environment_ready(env_name: str, max_size: int = PREFILTER_MAX_SIZE) -> bool:
    """Whether :func:`environment_basis` for these arguments is already in memory (returns at once)."""
    return (env_name, int(max_size)) in _READY


def view_environment(env_name: str) -> Environment:
    """The environment *env_name* (built-in name or .hdr/.exr path) at the viewer's width (ENV_WIDTH)."""
    check_environment(env_name)
    if env_name in ENVIRONMENTS:
        return procedural_environment(env_name, ENV_WIDTH)
    return load_environment_file(env_name)


@lru_cache(maxsize=8)
def _environment_basis(env_name: str, max_size: int) -> PrefilteredBasis:
    return prefilter_basis(
        view_environment(env_name),
        basis_exponents(),
        engine="numpy",
        cache=PrefilterCache(),
        max_size=max_size,
    )


def environment_basis_gl(env_name: str, ctx: Any) -> PrefilteredBasis:
    """The environment *env_name* prefiltered on the moderngl context *ctx* (current in this thread, e.g.
    the GL view's own), faces capped at PREFILTER_MAX_SIZE: the same tangent-grid quadrature as the
    NumPy engine of :func:`environment_basis` (``station.render.prefilter``, thesis §2.5.1), run as one
    render-to-texture pass per lobe (~0.5 s instead of 8–20 s on llvmpipe); maps are disk-cached under
    the ``gl`` engine. Not memoised here: the caller keeps the result (one per context). RenderError
    when the context cannot build the prefilter shaders."""
    return prefilter_basis(
        view_environment(env_name),
        basis_exponents(),
        engine="gl",
        cache=PrefilterCache(),
        ctx=ctx,
        max_size=PREFILTER_MAX_SIZE,
    )


@dataclass(frozen=True)
class ViewSettings:
    """What the 3D view shows: environment, shape, exposure (EV) and the orbit around the shape.

    ``environment`` is a built-in name (ENVIRONMENTS) or the path of an .hdr/.exr file
    (:meth:`ViewModel.load_environment`).
    ``yaw_deg``/``pitch_deg`` rotate the shape's default camera about the target (degrees),
    ``zoom`` divides the eye distance (1 = the default framing). ``misalignment_deg`` turns the right
    panel of the ``panels`` shape about its hinge (thesis ch. 4). ``stage`` shows the environment as
    backdrop over a ground with contact shadow (``station.render.stage.Stage``) instead of flat grey;
    ``coat`` adds the clear coat's Fresnel on the gloss (``station.model.gloss.ClearCoat``, index 1.5).
    ``flakes`` draws the effect paint's flake layer (sparkle and glints, ``station.render.flakes``; the
    paint type's default layer, :func:`station.model.design_io.default_flakes`) in every frame through
    the core's GL renderer; the level of detail may turn it off where flakes are below a pixel.
    ``flake_size_um``, ``flake_density``, ``flake_spread_deg`` replace that layer's size (µm), density
    (per mm²) and spread (degrees) when set (None: the paint type's default), within
    :data:`station.model.flakes.FLAKE_RANGES` (:meth:`flake_layer`).
    ``model``: the path of an own model (glTF/GLB, OBJ or STL, :meth:`ViewModel.load_model`), or the name
    of a built-in one (:data:`station.render.scene_image.BUILTIN_MESHES`: ``car``, the procedural car with
    wheels and glass), shown instead of the shape, framed by :data:`station.render.meshes.MESH_CAMERA`; None shows the shape.
    ``paint_part``: the model's part painted, by mesh or material name (a name of
    :func:`station.render.meshes.mesh_part_names`; :meth:`ViewModel.set_paint_part`), the other parts drawn
    as tyre, glass or chrome by their names, else neutral grey; None paints every part (a one-part GLB
    with a palette texture: its paint swatches, ``station.render.mesh_parts``).
    """

    environment: str = "booth"
    shape: str = "sphere"
    exposure_ev: float = 0.0
    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    zoom: float = 1.0
    misalignment_deg: float = 0.0
    stage: bool = False
    coat: bool = False
    flakes: bool = False
    flake_size_um: float | None = None
    flake_density: float | None = None
    flake_spread_deg: float | None = None
    model: str | None = None
    paint_part: str | None = None

    def __post_init__(self) -> None:
        check_environment(self.environment)
        if self.paint_part is not None and not (isinstance(self.paint_part, str) and self.paint_part.strip()):
            raise ViewInputError("paint_part", "a part name of the model, or none", self.paint_part)
        if self.model is not None and not (
            isinstance(self.model, str)
            and (self.model in BUILTIN_MESHES or Path(self.model).suffix.lower() in MESH_SUFFIXES)
        ):
            raise ViewInputError(
                "model", " | ".join((*BUILTIN_MESHES, *MESH_SUFFIXES)) + " file, or none", self.model
            )
        if self.shape not in SHAPES:
            raise ViewInputError("shape", " | ".join(SHAPES), self.shape)
        if not (math.isfinite(self.exposure_ev) and -10.0 <= self.exposure_ev <= 10.0):
            raise ViewInputError("exposure_ev", "-10 <= EV <= 10", self.exposure_ev)
        if not (math.isfinite(self.pitch_deg) and -80.0 <= self.pitch_deg <= 80.0):
            raise ViewInputError("pitch_deg", "-80 <= pitch <= 80", self.pitch_deg)
        if not (math.isfinite(self.zoom) and 0.5 <= self.zoom <= 4.0):
            raise ViewInputError("zoom", "0.5 <= zoom <= 4", self.zoom)
        if not (math.isfinite(self.misalignment_deg) and -45.0 <= self.misalignment_deg <= 45.0):
            raise ViewInputError("misalignment_deg", "-45 <= misalignment <= 45", self.misalignment_deg)
        for name in ("stage", "coat", "flakes"):
            if not isinstance(getattr(self, name), bool):
                raise ViewInputError(name, "true | false", getattr(self, name))
        if not math.isfinite(self.yaw_deg):
            raise ViewInputError("yaw_deg", "a finite angle", self.yaw_deg)
        for name, key in FLAKE_FIELDS.items():
            v = getattr(self, name)
            lo, hi = FLAKE_RANGES[key]
            if v is not None and not (isinstance(v, (int, float)) and lo <= v <= hi):
                raise ViewInputError(name, f"{lo:g} <= {name} <= {hi:g} or unset", v)

    def flake_layer(self, design: Any) -> FlakeLayer | None:
        """The flake layer drawn for *design*: None unless ``flakes``; else the paint type's default
        (:func:`station.model.design_io.default_flakes`; none for a solid) with the set fields put in."""
        from station.model.design_io import default_flakes

        if not self.flakes:
            return None
        layer = default_flakes(design)
        given = {
            key: getattr(self, name) for name, key in FLAKE_FIELDS.items() if getattr(self, name) is not None
        }
        if layer is None or not given:
            return layer
        return FlakeLayer(**{**layer.to_dict(), **given})

    def camera(self) -> Camera:
        """The orbit camera: the shape's default camera turned by yaw/pitch and moved in by zoom."""
        base = MESH_CAMERA if self.model is not None else DEFAULT_CAMERAS[self.shape]
        target = np.asarray(base.target, dtype=float)
        off = np.asarray(base.eye, dtype=float) - target
        dist = float(np.linalg.norm(off))
        pitch0 = math.degrees(math.asin(off[1] / dist))
        yaw0 = math.degrees(math.atan2(off[0], off[2]))
        pitch = math.radians(max(-85.0, min(85.0, pitch0 + self.pitch_deg)))
        yaw = math.radians(yaw0 + self.yaw_deg)
        d = dist / self.zoom
        eye = target + d * np.array(
            [math.cos(pitch) * math.sin(yaw), math.sin(pitch), math.cos(pitch) * math.cos(yaw)]
        )
        x, y, z = (float(v) for v in eye)
        return Camera((x, y, z), base.target, base.up, base.fov_deg)

    def scene(self) -> Scene:
        """The core scene (shape + orbit camera, and the stage when ``stage``)."""
        from station.render.stage import Stage

        return Scene(
            self.shape, self.misalignment_deg, camera=self.camera(), stage=Stage() if self.stage else None
        )

    def clear_coat(self) -> ClearCoat | None:
        """The clear coat shown (``coat``), or None for the thesis's model."""
        return ClearCoat() if self.coat else None

    def replace(self, **kw: Any) -> ViewSettings:
        """A copy with fields replaced (validated)."""
        return replace(self, **kw)


#: The view's flake fields and the FlakeLayer fields they set.
FLAKE_FIELDS = {
    "flake_size_um": "size_um",
    "flake_density": "density_per_mm2",
    "flake_spread_deg": "spread_deg",
}


def layer_weights(layout: tuple[tuple[str, int], ...], paint: LobeWeights) -> tuple[np.ndarray, np.ndarray]:
    """Per cached image j: (constant weight (K, 3), weight × c (K, 3)) of *paint*.

    The layout is ``station.render.basis_images``'s: ``("D", -1)`` diffuse map → w_D; ``("A", -1)`` the
    aspecular fall-off correction → w_A = π K_A (w_D includes π K_A) (:meth:`LobeWeights.fall_off_map_weight`); ``("Gh", i)``
    h_i·C_i → w_G,i; ``("Dg", i)`` g_i·C_i → w_DD,i; ``("C", i)`` C_i of a narrow lobe → w_G,i
    constant and w_DD,i times c = N·V (weights from :meth:`LobeWeights.map_weights`).
    """
    w_d, w_dd, w_g = paint.map_weights()
    const = np.zeros((len(layout), 3))
    times_c = np.zeros((len(layout), 3))
    for j, (kind, i) in enumerate(layout):
        if kind == "D":
            const[j] = w_d
        elif kind == "A":
            const[j] = paint.fall_off_map_weight()
        elif kind in ("Gh", "C", "Cg"):
            const[j] = w_g[i]
            if kind == "C":
                times_c[j] = w_dd[i]
        elif kind == "Cd":
            times_c[j] = w_dd[i]
        elif kind == "B":
            const[j] = 1.0  # the background share of an anti-aliased edge pixel
        else:
            const[j] = w_dd[i]
    return const, times_c


@dataclass(frozen=True, eq=False)
class BasisImages:
    """The core's cached basis images of one view (:func:`station.render.basis_images.build_basis_images`)
    as dense frames for the GPU: ``layers`` (K, H, W, 3) (zero off the object), N·V (H, W) and the paint id
    (H, W), −1 off the object, 0 or 1 on the two paint halves of the shape.
    """

    core: CoreBasisImages = field(repr=False)
    layers: np.ndarray = field(repr=False)
    n_dot_v: np.ndarray = field(repr=False)
    paint: np.ndarray = field(repr=False)
    prefilter_size: int = PREFILTER_MAX_SIZE

    @property
    def exponents(self) -> tuple[float, ...]:
        """Phong exponents of the basis."""
        return self.core.basis.exponents

    @property
    def layout(self) -> tuple[tuple[str, int], ...]:
        """What each layer holds (see :func:`layer_weights`)."""
        return self.core.layout

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return int(self.paint.shape[1]), int(self.paint.shape[0])

    @classmethod
    def compute(
        cls,
        settings: ViewSettings,
        width: int,
        height: int,
        prefilter_size: int = PREFILTER_MAX_SIZE,
        env: PrefilteredBasis | None = None,
        aa: int = 1,
    ) -> BasisImages:
        """Ray-cast the view and look up every prefiltered map once (the slow part, done per camera).

        *prefilter_size* caps the prefiltered cube faces (see :func:`environment_basis`); *env*: the
        prefiltered environment to use instead (e.g. :func:`environment_basis_gl`'s, full size); *aa*: samples
        per pixel at the silhouettes and paint seams (:func:`station.render.basis_images.build_basis_images`).
        """
        if env is None:
            env = environment_basis(settings.environment, prefilter_size)
        core = build_basis_images(settings.scene(), env, width, height, coat=settings.clear_coat(), aa=aa)
        k = core.images.shape[1]
        layers = np.zeros((k, height * width, 3), np.float32)
        layers[:, core.pixels] = core.images.transpose(1, 2, 0)
        ndv = np.zeros(height * width, np.float32)
        ndv[core.pixels] = core.n_dot_v
        paint = np.full(height * width, -1, np.int8)
        paint[core.pixels[: core.split]] = 0
        paint[core.pixels[core.split :]] = 1
        return cls(
            core,
            layers.reshape(k, height, width, 3),
            ndv.reshape(height, width),
            paint.reshape(height, width),
            int(prefilter_size),
        )

    def composite_linear(self, paints: tuple[LobeWeights, LobeWeights]) -> np.ndarray:
        """Linear sRGB radiance (H, W, 3) float32 of two paints (the core's re-weighting)."""
        return self.core.linear_image(list(paints))

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
        self._meshes: dict[tuple[str, str | None], Mesh] = {}  # (model path, paint part) → mesh
        self._parts: dict[str, tuple[str, ...]] = {}  # model path → its part names (mesh_part_names)
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

    def load_environment(self, path: str | Path) -> Environment:
        """Show the environment in the .hdr/.exr file *path* (read and checked now; the view then
        prefilters it). Raises ViewInputError for a path that is no .hdr/.exr file and
        EnvironmentFileError (names the file) for one that is not a usable HDR image; the settings are
        unchanged on failure. Returns the loaded environment."""
        env = load_environment_file(path)
        self.update(environment=str(Path(path)))
        return env

    def load_model(self, path: str | Path) -> Mesh:
        """Show the model in the glTF/GLB, OBJ or STL file *path* instead of the shape (read with
        :func:`station.render.meshes.load_mesh`, every part painted; the orbit reset), or the built-in
        model of that name (``car``: :func:`station.render.scene_image.builtin_mesh`, its body painted,
        its wheels and glass fixed). Raises RenderInputError (field ``mesh``, naming the file) for a file
        that cannot be used; the settings are unchanged on failure. Returns the mesh."""
        from station.render.meshes import load_mesh, mesh_part_names

        parts: tuple[str, ...] = ()
        if isinstance(path, str) and path in BUILTIN_MESHES:
            key, mesh = path, builtin_mesh(path)
        else:
            key = str(Path(path))
            mesh = load_mesh(key)
            parts = mesh_part_names(key)
        self._parts[key] = parts
        self._meshes[(key, None)] = mesh
        self.update(model=key, paint_part=None, yaw_deg=0.0, pitch_deg=0.0, zoom=1.0)
        return mesh

    def model_parts(self) -> tuple[str, ...]:
        """The part names of the model shown (mesh and material names, sorted), () when a shape is shown."""
        model = self._settings.model
        return () if model is None else self._parts.get(model, ())

    def set_paint_part(self, part: str | None) -> Mesh:
        """Paint the part *part* of the model shown (a name of :meth:`model_parts`; None: every part), the
        others drawn as tyre, glass or chrome by their names (``load_mesh(paint=part)``). Raises ViewInputError
        (field ``model``) when no model is shown and RenderInputError (field ``paint``, listing the parts) for
        a name no part has; the settings are unchanged on failure. Returns the mesh."""
        from station.render.meshes import load_mesh

        model = self._settings.model
        if model is None:
            raise ViewInputError("model", "a loaded model to pick the paint part of", None)
        if model in BUILTIN_MESHES and part is not None:
            raise ViewInputError("paint_part", f"none: the built-in {model}'s parts are fixed", part)
        key = (model, part)
        mesh = self._meshes.get(key)
        if mesh is None:
            mesh = self._meshes[key] = load_mesh(model, paint=part)
        self.update(paint_part=part)
        return mesh

    @property
    def models(self) -> tuple[str, ...]:
        """Paths of the models loaded so far (:meth:`load_model`), in loading order."""
        return tuple(self._parts)

    def mesh(self) -> Mesh | None:
        """The mesh of the model shown (``settings.model`` with its ``paint_part``), or None when a shape
        is shown."""
        model = self._settings.model
        return None if model is None else self._meshes.get((model, self._settings.paint_part))

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
