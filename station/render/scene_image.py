"""A design (or two, side by side) rendered in an environment on its stage: the picture the service returns.

The environment is a built-in procedural one (``station.render.procedural``) or an uploaded HDR file
(:func:`environment_from_bytes`: Radiance .hdr or OpenEXR .exr, bytes and pixels capped before the
pixels are decoded where the format allows). The picture is the NumPy renderer's
(:mod:`station.render.numpy_renderer`: same equations as the GL one, no GL stack needed by the service)
with the environment box-filtered to ENV_WIDTH and prefiltered to PREFILTER_SIZE faces, cached on disk
by content (:class:`~station.render.envcache.PrefilterCache`). Flakes are drawn as the GL renderer draws
them; a built-in mesh (:data:`BUILTIN_MESHES`) is rasterised by the GL renderer (the NumPy one ray-casts
the analytic shapes only); :func:`scene_lod` is the level of detail shared with ``station render --lod``.
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.model.flakes import FlakeLayer
from station.model.gloss import ClearCoat
from station.render.environment import Environment
from station.render.errors import EnvironmentFileError, RenderInputError
from station.render.flakes import FlakeChoice
from station.render.hdr_io import ACCEPTED, read_hdr_image
from station.render.options import FRAME_ENGINES
from station.render.shapes import Scene
from station.render.stage import Stage

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss
    from station.model.anisotropy import Anisotropy
    from station.render.meshes import Mesh
    from station.render.weights import LobeWeights

#: Largest uploaded environment file (bytes): a 1k Radiance file with RLE is about 1.4 MB.
MAX_UPLOAD_BYTES = 4 * 1_048_576
#: Longest base64 text of such a file in a JSON body (4 characters per 3 bytes, plus padding).
MAX_UPLOAD_BASE64_CHARS = (MAX_UPLOAD_BYTES * 4) // 3 + 4
#: Largest uploaded environment (pixels): 2048 × 1024.
MAX_UPLOAD_PIXELS = 2048 * 1024
#: Width the environment is box-filtered to before prefiltering (equirect, pixels).
ENV_WIDTH = 256
#: Cube face size of the prefiltered maps.
PREFILTER_SIZE = 32
#: Largest ΔE tolerance the service accepts for the level of detail (CIEDE2000).
LOD_MAX_DE = 10.0
_RADIANCE_SIZE = re.compile(rb"\n[-+]Y (\d+) [-+]X (\d+)\n")


def environment_from_bytes(data: bytes, field: str = "environment_hdr") -> Environment:
    """The environment in an uploaded .hdr/.exr file's bytes; RenderInputError naming *field* when it is
    empty, over MAX_UPLOAD_BYTES or MAX_UPLOAD_PIXELS, or not a usable HDR image."""
    if not data:
        raise RenderInputError(field, ACCEPTED, None, "an empty file")
    if len(data) > MAX_UPLOAD_BYTES:
        raise RenderInputError(
            field, f"a file of at most {MAX_UPLOAD_BYTES} bytes", None, f"{len(data)} bytes"
        )
    if data.startswith((b"#?RADIANCE", b"#?RGBE")):
        m = _RADIANCE_SIZE.search(data[:4096])
        if m is None:
            raise RenderInputError(field, ACCEPTED, None, "no resolution line in the Radiance header")
        h, w = int(m.group(1)), int(m.group(2))
        if h * w > MAX_UPLOAD_PIXELS:
            raise RenderInputError(field, f"at most {MAX_UPLOAD_PIXELS} pixels", None, f"{w}x{h}")
    suffix = ".exr" if data.startswith(b"\x76\x2f\x31\x01") else ".hdr"
    with tempfile.TemporaryDirectory(prefix="cacad-env-") as tmp:
        path = Path(tmp) / f"upload{suffix}"
        path.write_bytes(data)
        try:
            image = read_hdr_image(path)
        except EnvironmentFileError as exc:
            raise RenderInputError(field, ACCEPTED, None, exc.detail) from None
    if image.shape[0] * image.shape[1] > MAX_UPLOAD_PIXELS:
        raise RenderInputError(
            field, f"at most {MAX_UPLOAD_PIXELS} pixels", None, f"{image.shape[1]}x{image.shape[0]}"
        )
    if image.shape[1] != 2 * image.shape[0]:
        raise RenderInputError(
            field, "an equirectangular map (width = 2 × height)", None, f"{image.shape[1]}x{image.shape[0]}"
        )
    return Environment("upload", image)


#: Built-in meshes a request may name (no files: generated on demand).
BUILTIN_MESHES = ("car",)


@dataclass(frozen=True)
class SceneImage:
    """A rendered picture and what the level of detail chose: ``flakes`` (the flake layer's
    :class:`~station.render.flakes.FlakeChoice`, None without one), ``lod`` (lobes and environment width
    for a ΔE tolerance, :func:`scene_lod`, None without a tolerance) and the ``engine`` (numpy | gl)."""

    image: np.ndarray
    flakes: FlakeChoice | None
    lod: dict[str, Any] | None
    engine: str


def builtin_mesh(name: str) -> Mesh:
    """The built-in mesh *name* (BUILTIN_MESHES: ``car``, the procedural car body)."""
    from station.render.car import car_body

    if name not in BUILTIN_MESHES:
        raise RenderInputError("mesh", " | ".join(BUILTIN_MESHES), name)
    return car_body()


@dataclass(frozen=True, eq=False)
class FrameOptions:
    """How a frame is drawn, as its level of detail is judged on it (:class:`FrameProbe`, :func:`scene_lod`).

    Attributes
    ----------
    engine
        The renderer, gl | numpy | truth (the truth has no level of detail: :class:`FrameProbe` refuses it).
    prefilter_engine, max_size
        The environment prefiltered by gl | numpy, capped at *max_size* cube faces (``None``: no cap).
    coat
        The clear coat (``None``: the thesis's model).
    mesh
        The mesh drawn instead of the scene's shape (gl only).
    aa
        Samples per pixel (gl).
    anisotropy
        The paint's anisotropy (gl only).
    """

    engine: str = "numpy"
    prefilter_engine: str = "numpy"
    max_size: int | None = PREFILTER_SIZE
    coat: ClearCoat | None = None
    mesh: Mesh | None = None
    aa: int = 1
    anisotropy: Anisotropy | None = None

    def __post_init__(self) -> None:
        if self.engine not in FRAME_ENGINES:
            raise RenderInputError("engine", " | ".join(FRAME_ENGINES), self.engine)
        if self.prefilter_engine not in ("gl", "numpy"):
            raise RenderInputError("prefilter_engine", "gl | numpy", self.prefilter_engine)
        if self.mesh is not None and self.engine != "gl":
            raise RenderInputError("engine", "gl for a mesh", self.engine)
        if self.anisotropy is not None and self.engine != "gl":
            raise RenderInputError("engine", "gl for a design with anisotropy", self.engine)


class FrameProbe:
    """A frame drawn at any level-of-detail setting (:class:`station.render.lod.FrameSetting`) and size by
    the frame's own renderer as *options* (:class:`FrameOptions`) say, the environment's prefiltered maps
    cached in *cache*, the stage of *scene*; no flakes (their sparkle has a level of detail of its own,
    :func:`station.render.flakes.flake_lod`). A context manager (it may hold a GL context)."""

    def __init__(
        self,
        designs: Sequence[FaceFlopTravelGloss],
        environment: Environment,
        scene: Scene,
        options: FrameOptions | None = None,
        *,
        cache: Any = None,
    ) -> None:
        o = FrameOptions() if options is None else options  # FrameOptions checks its own fields
        if o.engine == "truth":
            raise RenderInputError("engine", "gl | numpy (the truth engine has no level of detail)", o.engine)
        self.designs, self.environment, self.scene = list(designs), environment, scene
        self.options, self.cache = o, cache
        self.ctx: Any = None
        if o.engine == "gl" or o.prefilter_engine == "gl":
            from station.render.gl_context import create_gl_context

            self.ctx = create_gl_context()
        self._bases: dict[tuple[int | None, int | None], tuple[Any, list[LobeWeights]]] = {}
        # the clear coat's diffuse maps per environment width, shared by that width's bases (the map
        # depends on the environment and the coat, not on the lobes)
        self._coat_maps: dict[int | None, dict[float, np.ndarray]] = {}

    def __enter__(self) -> FrameProbe:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Release the GL context (if any)."""
        if self.ctx is not None:
            self.ctx.release()
            self.ctx = None

    def setup(self, setting: Any) -> tuple[Any, list[LobeWeights]]:
        """(prefiltered basis, paints) of *setting*'s lobes and environment width."""
        from station.render import lobe_fit
        from station.render.lobes import basis_for_count, default_basis
        from station.render.prefilter import prefilter_basis

        key = (setting.lobes, setting.environment_width)
        if key not in self._bases:
            lobes = default_basis() if setting.lobes is None else basis_for_count(setting.lobes)
            env = self.environment
            if setting.environment_width is not None:
                env = env.downsampled(setting.environment_width)
            paints = [lobe_fit.fit_design(d, lobes) for d in self.designs]
            basis = prefilter_basis(
                env,
                paints[0].exponents,
                engine=self.options.prefilter_engine,
                cache=self.cache,
                ctx=self.ctx,
                max_size=self.options.max_size,
            )
            shared = self._coat_maps.setdefault(setting.environment_width, basis.coat_maps)
            self._bases[key] = (replace(basis, coat_maps=shared), paints)
        return self._bases[key]

    def draw(self, setting: Any, size: int, bare: bool = False) -> np.ndarray:
        """Linear sRGB (size, size, 3) of the frame at *setting* (*bare*: without the stage)."""
        from station.render.numpy_renderer import render_linear

        basis, paints = self.setup(setting)
        o, scene = self.options, self.scene
        if bare and scene.stage is not None:
            scene = Scene(scene.shape, misalignment_deg=scene.misalignment_deg, camera=scene.view_camera)
        if o.engine == "numpy":
            return np.asarray(render_linear(scene, basis, paints, size, size, coat=o.coat))
        from station.render.gl_renderer import GLRenderer

        with GLRenderer(basis, size, size, ctx=self.ctx, aa=o.aa) as gl:
            return gl_frame(gl, scene, paints, o, anisotropic_samples=setting.anisotropic_samples)

    def mask(self, size: int) -> np.ndarray:
        """The painted pixels (size, size) bool: the shape's inside its silhouette (:func:`interior_mask`),
        or, for a mesh, those of a frame without a stage that differ from its background corner."""
        from station.render import lod as lodm

        if self.options.mesh is None:
            return interior_mask(self.scene, size)
        bare = self.draw(lodm.DEFAULT_SETTING, size, bare=True)
        return np.asarray(np.any(np.abs(bare - bare[:1, :1]) > 1e-6, axis=-1))


def gl_frame(
    gl: Any,
    scene: Scene,
    paints: Sequence[LobeWeights],
    options: FrameOptions,
    *,
    flakes: FlakeLayer | None = None,
    anisotropic_samples: int | None = None,
) -> np.ndarray:
    """Linear sRGB radiance (H, W, 3) of *scene* drawn by the GL renderer *gl*
    (:class:`~station.render.gl_renderer.GLRenderer`) as *options* say: their mesh on the scene's stage
    seen by the scene's camera, else the scene's shape; their clear coat and anisotropy, with *flakes* and
    *anisotropic_samples* off-specular samples (``None``: the renderer's own choice)."""
    if options.mesh is not None:
        return np.asarray(
            gl.render_mesh(
                options.mesh,
                paints,
                camera=scene.view_camera,
                stage=scene.stage,
                coat=options.coat,
                linear=True,
                flakes=flakes,
                anisotropy=options.anisotropy,
                anisotropic_samples=anisotropic_samples,
            )
        )
    return np.asarray(
        gl.render_linear(
            scene,
            paints,
            coat=options.coat,
            flakes=flakes,
            anisotropy=options.anisotropy,
            anisotropic_samples=anisotropic_samples,
        )
    )


def interior_mask(scene: Scene, size: int) -> np.ndarray:
    """The shape's pixels (size, size) whose four neighbours are the shape's too: where a frame's shading,
    not its silhouette's anti-aliasing, is compared with the truth engine's."""
    from station.render.numpy_renderer import gbuffer

    m = np.asarray(gbuffer(scene, size, size).mask, dtype=bool)
    inner = m.copy()
    inner[1:] &= m[:-1]
    inner[:-1] &= m[1:]
    inner[:, 1:] &= m[:, :-1]
    inner[:, :-1] &= m[:, 1:]
    inner[0, :] = inner[-1, :] = inner[:, 0] = inner[:, -1] = False
    return inner


def scene_lod(
    designs: Sequence[FaceFlopTravelGloss],
    environment: Environment,
    scene: Scene,
    tolerance_de: float,
    options: FrameOptions | None = None,
    *,
    cache: Any = None,
    size: int | None = None,
) -> tuple[list[LobeWeights], Environment, dict[str, Any]]:
    """Level of detail of the frame for a CIEDE2000 tolerance (:func:`station.render.lod.choose_frame_lod`):
    each candidate (lobe count, environment width, anisotropic samples) is rendered by the frame's own
    renderer as *options* say (:class:`FrameOptions`: engine, prefilter, coat, mesh, samples per pixel,
    anisotropy; the stage of *scene*; no flakes) at ``min(PROBE_SIZE, size)`` pixels and judged against
    the renderer's most accurate setting, with the declared probe-to-truth margin. *cache*: a
    :class:`~station.render.envcache.PrefilterCache`.

    Returns the paints fitted with the chosen basis, the environment at the chosen width, and the report
    (lobes, environment width, anisotropic samples (None: the renderer's own choice), met, estimate,
    margin, the default's estimate, the description)."""
    from station.render import lobe_fit
    from station.render import lod as lodm
    from station.render.lobes import basis_for_count, default_basis

    if not (np.isfinite(tolerance_de) and tolerance_de > 0):
        raise RenderInputError("tolerance_de", "a CIEDE2000 tolerance > 0", tolerance_de)
    options = FrameOptions() if options is None else options
    probe_size = lodm.PROBE_SIZE if size is None else max(8, min(lodm.PROBE_SIZE, int(size)))
    with FrameProbe(designs, environment, scene, options, cache=cache) as probe:
        mask = probe.mask(probe_size)
        if not mask.any():
            raise RenderInputError("lod", "a view that shows the shape", tolerance_de)
        choice = lodm.choose_frame_lod(
            lambda st: probe.draw(st, probe_size),
            lodm.scene_white(environment),
            tolerance_de,
            lodm.frame_candidates(int(environment.equirect.shape[1])),
            mask=mask,
            anisotropic=options.anisotropy is not None,
            probe_size=probe_size,
        )
    s = choice.setting
    lobes = default_basis() if s.lobes is None else basis_for_count(s.lobes)
    paints = [lobe_fit.fit_design(d, lobes) for d in designs]
    env = environment if s.environment_width is None else environment.downsampled(s.environment_width)
    report = {
        "lobes": len(lobes.exponents),
        "default_lobes": s.lobes is None,
        "environment_width": int(env.equirect.shape[1]),
        "anisotropic_samples": s.anisotropic_samples,
        "met": choice.met,
        "errors": {
            "estimate": round(choice.estimate_de, 3),
            "margin": round(choice.margin_de, 3),
            "total": round(choice.estimate_de + choice.margin_de, 3),
            "default": round(choice.default_estimate_de, 3),
        },
        "probe_size": probe_size,
        "engine": options.engine,
        "describe": choice.describe(),
    }
    return paints, env, report


def render_scene_image(
    designs: Sequence[FaceFlopTravelGloss],
    environment: Environment,
    *,
    shape: str = "speedshape",
    stage: Stage | None = None,
    coat: ClearCoat | None = None,
    exposure_ev: float = 0.0,
    size: int = 256,
    flakes: FlakeLayer | None = None,
    mesh: str | None = None,
    lod_de: float | None = None,
) -> SceneImage:
    """8-bit sRGB picture (size, size, 3) of one design (both halves) or two (left | right) in
    *environment* on *stage* with the clear coat *coat* (None: the thesis's model), the flake layer
    *flakes* (drawn where the level of detail keeps it), on *shape* or a built-in *mesh* (GL: needs an
    OpenGL stack, GLUnavailableError otherwise), with the lobes and environment width chosen for the
    CIEDE2000 tolerance *lod_de* (None: the default basis at ENV_WIDTH)."""
    from station.render import lobe_fit, tonemap
    from station.render.envcache import PrefilterCache
    from station.render.flakes import flake_lod
    from station.render.numpy_renderer import render_linear
    from station.render.prefilter import prefilter_basis

    if not 1 <= len(designs) <= 2:
        raise RenderInputError("designs", "one or two designs", len(designs))
    scene = Scene(shape, stage=stage)
    env = environment.downsampled(ENV_WIDTH) if environment.equirect.shape[1] > ENV_WIDTH else environment
    lod = None
    if lod_de is not None:
        model = builtin_mesh(mesh) if mesh is not None else None
        options = FrameOptions("gl" if model is not None else "numpy", coat=coat, mesh=model)
        paints, env, lod = scene_lod(designs, env, scene, lod_de, options, cache=PrefilterCache(), size=size)
    else:
        paints = [lobe_fit.fit_design(d) for d in designs]
    basis = prefilter_basis(
        env, paints[0].exponents, engine="numpy", cache=PrefilterCache(), max_size=PREFILTER_SIZE
    )
    if mesh is not None:
        from station.render.gl_renderer import GLRenderer

        model = builtin_mesh(mesh)
        with GLRenderer(basis, size, size) as gl:
            linear = gl.render_mesh(model, paints, stage=stage, coat=coat, linear=True, flakes=flakes)
            return SceneImage(tonemap.to_display(linear, exposure_ev), gl.last_flakes, lod, "gl")
    linear = render_linear(scene, basis, paints, size, size, coat=coat, flakes=flakes)
    choice = None if flakes is None else flake_lod(flakes, scene.view_camera, size)
    return SceneImage(tonemap.to_display(linear, exposure_ev), choice, lod, "numpy")


def render_design_image(
    designs: Sequence[FaceFlopTravelGloss],
    environment: Environment,
    *,
    shape: str = "speedshape",
    stage: Stage | None = None,
    coat: ClearCoat | None = None,
    exposure_ev: float = 0.0,
    size: int = 256,
) -> np.ndarray:
    """8-bit sRGB picture (size, size, 3) of one design (both halves) or two (left | right) in
    *environment* on *stage* with the clear coat *coat* (None: the thesis's model)."""
    return render_scene_image(
        designs, environment, shape=shape, stage=stage, coat=coat, exposure_ev=exposure_ev, size=size
    ).image
