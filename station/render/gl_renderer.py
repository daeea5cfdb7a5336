"""OpenGL (moderngl) side of the renderer: the GL renderer.

Every GL object is created from a context made by :func:`station.render.gl_context.create_gl_context`
(a headless EGL context: Mesa llvmpipe on CPU-only machines, the GPU driver where one exists) and released
explicitly; :class:`GLRenderer` is a context manager. The context factory and shader loader live in
:mod:`station.render.gl_context`, re-exported here for callers that import them from this module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from station.closing import Closing
from station.model.anisotropy import Anisotropy
from station.model.flakes import FlakeLayer
from station.model.gloss import ClearCoat
from station.render import gl_textures as tx
from station.render.errors import RenderInputError
from station.render.flakes import FlakeChoice, flake_lod, flake_uniforms
from station.render.gl_anisotropy import anisotropy_frame
from station.render.gl_context import (
    GL_TEXTURE_CUBE_MAP_SEAMLESS,
    SHADER_DIR,
    build_program,
    create_gl_context,
    gl_available,
    load_shader,
)
from station.render.gl_frame_shadows import COARSE_UNIT, FrameShadows
from station.render.gl_light_maps import ShadowedMaps
from station.render.gl_maps import DerivedMaps
from station.render.gl_passes import FramePasses
from station.render.gl_programs import binding_order, compiled_terms, renderer_defines, set_uniforms
from station.render.gl_targets import FrameTargets
from station.render.horizon_poly import horizon_chebyshev
from station.render.numpy_renderer import (
    BACKGROUND,
    HORIZON_MAX_EXPONENT,
    check_paints,
    check_size,
    horizon_table,
    horizon_wide,
)
from station.render.sh import sh_diffuse_matrix
from station.render.shapes import GROUNDS, OCCLUDERS, Scene
from station.render.stage import MAX_OCCLUDERS, backdrop_lobe, lookup_matrix, stage_bits
from station.render.tonemap import CURVES, check_curve

if TYPE_CHECKING:
    from station.render.lod import AnisotropyChoice

__all__ = [
    "GL_TEXTURE_CUBE_MAP_SEAMLESS",
    "SHADER_DIR",
    "GLRenderer",
    "build_program",
    "create_gl_context",
    "gl_available",
    "load_shader",
]

#: Texels per side of the baked ground map (the disc's square; 6-unit radius: 1.2 cm a texel, a 1°
#: penumbra at 2 units from its occluder spans ~6 texels).
GROUND_MAP = 1024


class GLRenderer(Closing):
    """Renders scenes with one prefiltered basis on a GL context; a context manager.

    The lobe maps are uploaded once as half-float (``half_float=True``) or float cube textures. One
    program is built per (shape, output kind) on first use. :meth:`render` returns the 8-bit sRGB
    frame (tone mapped in the shader), :meth:`render_linear` float radiance; both row 0 at the top.

    With ``combined=True`` (default) the narrow lobes of both paints are pre-summed on the GPU, whenever
    the weights change, into a gloss atlas Σ w_G,i C_i and a directionally diffuse atlas Σ w_DD,i C_i at
    the largest lobe resolution (``shaders/combine.frag.glsl``, cube faces with seamless borders), so
    the narrow lobes cost two lookups per pixel whatever their count and without a branch on the paint;
    the wide lobes (horizon factors, exact lights, bent lookups) are looked up per lobe, and weight groups
    that are all zero are compiled out (:meth:`_terms`). ``combined=False`` looks every lobe up per
    pixel. The lights and exponents are compiled in (the loops unroll), and the ground of a stage is
    baked into a map once per stage (:meth:`_ground_map`).

    ``coat`` (of :meth:`render` / :meth:`render_linear`): a :class:`station.model.gloss.ClearCoat` scales
    the gloss terms per pixel by the coat's exact Fresnel and the base by what it transmits, the diffuse
    term read from the coat-transmitted diffuse map (as ``numpy_renderer`` does); None: the thesis's model.

    ``anisotropy`` (same methods): a :class:`station.model.anisotropy.Anisotropy` replaces both paints'
    gloss lobes by Ward's anisotropic lobe of that (α_x, α_y, direction), with P_s the paint's gloss
    energy Σ w_G,i (kept at every view unless :attr:`anisotropy_energy` is "ward"), rendered by
    off-specular samples (eqs 2.5.4–2.5.7, ``shaders/anisotropy.glsl``, the equations of
    :func:`station.render.anisotropy.shade_anisotropic`). The sample count is
    ``anisotropic_samples`` when given, else the level of detail's choice for this environment and
    :attr:`anisotropy_tolerance_de` (:func:`station.render.lod.choose_anisotropic_samples`), reported in
    :attr:`last_anisotropy`. None (default) compiles none of it in: the isotropic path is unchanged.

    ``aa``: anti-aliasing, samples per pixel (1, 4, 9 or 16; :mod:`station.render.gl_targets`): the
    frame is shaded at √aa times the size and box-resolved on the GPU; 1 (default) draws at the size.

    ``shadowed_maps``: where a shadow map hides a light, the narrow lobes and the flakes' glints read their
    maps without that light (:mod:`station.render.gl_light_maps`); False keeps the light in them (the
    renderer before, for comparison).
    """

    def __init__(
        self,
        basis,
        width: int,
        height: int,
        ctx=None,
        diffuse: str = "cube",
        half_float: bool = True,
        combined: bool = True,
        horizon: str = "lut",
        aa: int = 1,
        shadowed_maps: bool = True,
    ) -> None:
        check_size(width, height)
        if diffuse not in ("cube", "sh"):
            raise RenderInputError("diffuse", "cube | sh", diffuse)
        self.basis = basis
        self.width, self.height = int(width), int(height)
        self.diffuse = diffuse
        self._own_ctx = ctx is None
        self.ctx = create_gl_context() if ctx is None else ctx
        self.combined = combined
        self._half_float = half_float
        self._atlas_face = max(c.shape[1] for c in basis.cubes)
        self._horizon = horizon
        self._wide, self._order, self._lights = binding_order(basis, horizon, HORIZON_MAX_EXPONENT)
        self._n_wide = int(self._wide.sum())
        self._lobes = [tx.cube_texture(self.ctx, basis.cubes[i], half_float) for i in self._order]
        narrow = (self._wide[self._order] == 0).astype(np.float32)  # the atlases' lobes (combine.frag.glsl)
        self._narrow_atlas = tx.NarrowAtlas(self.ctx, self._lobes, narrow, self._atlas_face, half_float)
        self._diffuse_tex = tx.cube_texture(self.ctx, basis.diffuse, half_float)
        table = horizon_table(basis.exponents, horizon)[self._order]  # (m, N, 2): rows = bound lobes
        self._horizon_tex = tx.horizon_texture(self.ctx, table)
        self._maps = DerivedMaps(self.ctx, basis, half_float)  # flake mean, coat diffuse, coat base maps
        bound_exps = np.asarray(basis.exponents)[self._order]
        self._defines = renderer_defines(
            n_lobes=len(self._lobes),
            diffuse=diffuse,
            combined=combined,
            horizon=horizon,
            horizon_n=table.shape[1],
            atlas_face=self._atlas_face,
            diffuse_face=self._maps.base_face,
            n_wide=self._n_wide,
            n_lights=self._lights.count if self._lights is not None else 0,
            bound_exponents=bound_exps,
            horizon_cheb=horizon_chebyshev(
                bound_exps, table, horizon_wide([float(e) for e in bound_exps], horizon)
            ),
        )
        self._sh = sh_diffuse_matrix(basis.sh)
        lit = self._lights is not None and self._lights.pixels is not None  # gl_light_maps: lights' pixels
        self._defines["SHADOWED_MAPS"] = int(lit and shadowed_maps)  # the class doc
        self._passes = FramePasses(self.ctx, self._defines)  # programs, footprint buffer, pass drawing
        self._mesh = tx.MeshArrays(self.ctx)
        #: Draw a shape over its screen footprint (:mod:`station.render.gl_passes`). False: one full-screen
        #: pass of the paint program (the same frame, every pixel paying for the paint).
        self.footprint = True
        #: The smooth terms at a coarser rate where they allow it (:meth:`FramePasses.frame_footprint`).
        self.coarse_smooth = True
        self.mesh_prepass = True  # a mesh's depth first, each pixel shaded once (FramePasses._draw_mesh)
        self.last_coarse = 0  # the last frame's coarse factor k (0: none)
        #: The flake level-of-detail choice of the last frame (:func:`station.render.flakes.flake_lod`).
        self.last_flakes: FlakeChoice | None = None
        #: Targets at the shading size and the anti-aliasing resolve (``aa`` samples per pixel).
        self.targets = FrameTargets(self.ctx, self.width, self.height, aa)
        #: ΔE00 tolerance the level of detail meets when it picks the anisotropic sample count.
        self.anisotropy_tolerance_de = 1.0
        #: Energy of the anisotropic lobe (:data:`station.render.anisotropy.ENERGIES`): "design" keeps the
        #: paint's gloss energy at every view; "ward" is eq 2.5.4's, times its albedo A(N, V).
        self.anisotropy_energy = "design"
        #: The anisotropic sample choice of the last frame (None: isotropic frame).
        self.last_anisotropy: AnisotropyChoice | None = None
        self._aniso: dict[tuple, tuple] = {}
        #: Shadow maps of the strongest extracted lights and the ground's occlusion under a mesh or a shape
        #: (:mod:`station.render.gl_frame_shadows`), False: the proxies'; object_shadows False: the ground's only.
        self.shadows = True
        self.object_shadows = True
        maps = ShadowedMaps(self.ctx, basis, self._order, narrow, self._atlas_face, half_float)
        self._frame_shadows = FrameShadows(self.ctx, self._lights, maps if lit else None)

    def set_aa(self, aa: int) -> None:
        """Switch anti-aliasing to *aa* samples per pixel (:data:`station.render.gl_targets.AA_SAMPLES`):
        new targets, the maps and programs kept (e.g. a view shaded once per pixel while it moves and
        supersampled once it is still); RenderInputError naming ``aa`` as the constructor."""
        if aa == self.targets.aa:
            return
        targets = FrameTargets(self.ctx, self.width, self.height, aa)
        self.targets.release()
        self.targets = targets

    def _terms(self, pair) -> tuple[int, int, int]:
        """Which weight groups of these paints are non-zero: (:func:`station.render.gl_programs.compiled_terms`,
        1 when either paint has an aspecular fall-off K_A and the horizon tables are on). Without the
        combined maps every lobe is looked up (mask -1)."""
        fall_off = int(self._horizon != "none" and any(w.has_fall_off for w in pair))
        if not self.combined:
            return (-1, 1, fall_off)
        mask, narrow_dd = compiled_terms([self._bound_weights(w) for w in pair], self._wide[self._order])
        return (mask, narrow_dd, fall_off)

    def _bound_weights(self, w):
        """map_weights() of *w* with the lobes in binding order."""
        w_d, w_dd, w_g = w.map_weights()
        return w_d, w_dd[self._order], w_g[self._order]

    def _draw(
        self,
        scene,
        paints,
        linear: bool,
        exposure_ev: float,
        curve: str,
        coat: ClearCoat | None,
        mesh=None,
        flakes: FlakeLayer | None = None,
        target=None,
        anisotropy: Anisotropy | None = None,
        anisotropic_samples: int | None = None,
        probe: bool = False,
    ):
        """One frame into *target* (default this renderer's framebuffer): the frame's features and
        programs (:meth:`_frame_programs`), textures bound and uniforms set (:meth:`_frame_uniforms`), then
        the shape's full-screen pass, or the stage pass and the rasterised mesh."""
        pair = check_paints(self.basis, paints)
        self.last_flakes = flake_lod(flakes, scene.view_camera, self.targets.shade_size[1])
        if not linear:
            check_curve(curve)
        pair, passes, aniso_uniforms, occluders, n_occ, objects = self._frame_programs(
            scene,
            pair,
            linear,
            0 if linear else CURVES.index(curve),
            coat,
            mesh,
            anisotropy,
            anisotropic_samples,
            self.last_flakes.on,
            probe,
        )
        shadow = self._frame_shadows.key(scene, mesh, self.shadows, probe)
        glints = flakes if self.last_flakes.on else None
        if shadow:  # before the frame binds its own: these draws bind their own targets and textures
            self._frame_shadows.update(scene, mesh, objects, [self._bound_weights(w) for w in pair], glints)
        own = target is None or self.targets.side > 1 or mesh is not None
        fbo = self.targets.draw_target(linear, depth=mesh is not None) if own else target
        fbo.use()
        occ = np.zeros((MAX_OCCLUDERS, 4), np.float32)
        occ[: len(occluders)] = occluders
        uniforms, mw, m = self._frame_uniforms(scene, pair, fbo, coat, mesh, flakes, aniso_uniforms)
        if not linear:
            uniforms["u_exposure"] = float(2.0**exposure_ev)
        if shadow:
            uniforms.update(self._frame_shadows.bind(scene, mesh, m, objects, mw, glints))
        if scene.stage is not None and scene.stage.ground:
            self._ground_map(uniforms, mw, occ, n_occ, m, shadow).use(m + 2)
            fbo.use()
            uniforms["u_ground_map"] = m + 2
        for prog, _ in passes:
            self._set_uniforms(prog, uniforms, mw, occ, m)
        self._passes.bind_coarse(passes, self.targets.shade_size, self.last_coarse, m + COARSE_UNIT)
        self._passes.draw(fbo, passes, mesh, self._mesh, probe, self.mesh_prepass)
        if fbo is target or (self.targets.side == 1 and target is None):
            return fbo
        if self.targets.side == 1:  # a mesh drawn with its depth buffer, then blitted into *target*
            self.ctx.copy_framebuffer(target, fbo)
            return target
        out = target if target is not None else self.targets.output_target(linear)
        return self.targets.resolve(fbo, out)

    def _frame_programs(
        self,
        scene,
        pair,
        linear: bool,
        curve_i: int,
        coat,
        mesh,
        anisotropy,
        anisotropic_samples,
        flakes_on: bool = False,
        probe: bool = False,
    ) -> tuple[list, list, dict, np.ndarray, int, tuple]:
        """(paints, passes, anisotropy uniforms, sphere occluders (k, 4), occluders compiled in, the object's
        shadow key FrameShadows.object_key) of one frame: the features compiled in (coat, stage bits, flakes,
        anisotropy) and the programs."""
        lights_out = [bool(w) for w in self.basis.wide] if self._lights is not None else []
        bits = stage_bits(scene.stage, self.basis.exponents, lights_out)  # lights out of the backdrop's map
        feats: tuple[int, ...] = (int(coat is not None), bits, int(flakes_on))
        aniso_uniforms: dict = {}
        if anisotropy is not None:
            pair, aniso_uniforms, self.last_anisotropy = anisotropy_frame(
                self.ctx,
                self.basis,
                self._order,
                self._aniso,
                pair,
                anisotropy,
                anisotropic_samples,
                self.anisotropy_tolerance_de,
                self.anisotropy_energy,
            )
            feats = (*feats, 1)
        else:
            self.last_anisotropy = None
        terms = self._terms(pair)
        if mesh is None:
            occluders = np.asarray(OCCLUDERS[scene.shape], np.float32).reshape(-1, 4)
        else:
            occluders = mesh.occluders().astype(np.float32)
        n_occ = len(occluders) if scene.stage is not None else 0
        shadow = self._frame_shadows.object_key(scene, mesh, self.shadows, self.object_shadows, probe)
        if mesh is not None:
            passes = self._passes.mesh_passes(linear, feats, terms, n_occ, curve_i, shadow, self.mesh_prepass)
        else:
            bw = [self._bound_weights(w) for w in pair]  # the paints' bound weights
            foot, k = self._passes.frame_footprint(
                scene, self.targets.shade_size, bw, self.coarse_smooth, self.footprint, probe
            )
            passes = self._passes.shape_passes(
                scene.shape, foot, linear, feats, terms, n_occ, curve_i, shadow, bool(k)
            )
        self.last_coarse = k if mesh is None and len(passes) == 4 else 0
        return pair, passes, aniso_uniforms, occluders, n_occ, shadow

    def _frame_uniforms(
        self, scene, pair, fbo, coat, mesh, flakes, aniso_uniforms: dict
    ) -> tuple[dict, list, int]:
        """Bind the frame's textures and return (uniforms, bound weights of the paints, lobe count m)."""
        two = (pair + pair)[:2]
        w_a = [w.fall_off_map_weight() for w in two]  # pi K_A per paint
        w_k = [w.map_weights()[0] - a for w, a in zip(two, w_a, strict=True)]  # pi K_D: under a coat, D_coat
        mw = [self._bound_weights(w) for w in pair]
        coat_tex = base_tex = None
        if coat is not None:  # made first: their sums on this context bind their own target and textures
            coat_tex = self._maps.coat_diffuse(coat)
            if self.combined and self.diffuse == "cube":  # shaders/render.frag.glsl's DIFFUSE_ATLAS
                base_tex = self._maps.coat_base(self._diffuse_tex, coat, w_a, w_k)
            fbo.use()
        stage = scene.stage
        backdrop = backdrop_lobe(self.basis.exponents, stage.backdrop_blur_deg if stage is not None else 0.0)
        gx, gy, gz = GROUNDS[scene.shape] if mesh is None else (0.0, mesh.floor_y, 0.0)
        m = len(self._lobes)
        if self.combined:
            cubes = self._narrow_atlas.atlases(mw)
            fbo.use()
            for unit, tex in enumerate(cubes):
                tex.use(m + unit)
        for unit, tex in enumerate(self._lobes):
            tex.use(unit)
        self._diffuse_tex.use(m + 4)
        if coat_tex is not None:
            coat_tex.use(m + 3)
        if base_tex is not None:
            base_tex.use(m + 10)
        self._horizon_tex.use(m + 5)
        self._lobes[int(np.nonzero(self._order == backdrop)[0][0])].use(m + 6)
        uniforms = {
            **scene.view_camera.uniforms(*self.targets.shade_size),
            "u_size": tuple(float(v) for v in self.targets.shade_size),
            "u_misalign": float(np.radians(scene.misalignment_deg)),
            "u_background": (BACKGROUND,) * 3,
            "u_diffuse": m + 4,
            "u_horizon": m + 5,
            "u_coat_n": coat.index if coat is not None else 1.5,
            "u_coat_ref": coat.reference if coat is not None else 1.0,
            "u_coat_t": coat.diffuse_transmission if coat is not None else 1.0,
            "u_diffuse_coat": m + 3,
            "u_diffuse_base": m + 10,
            # u_rot column-major: the matrix's transpose, row by row
            "u_rot": tuple(float(v) for v in lookup_matrix(stage.rotation_deg if stage else 0.0).T.ravel()),
            "u_backdrop": m + 6,
            "u_backdrop_exp": float(self.basis.exponents[backdrop]),
            "u_ground_y": float(gy),
            "u_ground_c": (float(gx), float(gz)),
            "u_ground_albedo": stage.ground_albedo if stage is not None else 0.0,
            "u_ground_radius": stage.ground_radius if stage is not None else 1.0,
            "u_flake_sharp": m + 7,
            "u_flake_mean": m + 8,
        }
        on = flakes is not None and self.last_flakes is not None and self.last_flakes.on
        if on:
            uniforms.update(flake_uniforms(flakes))
            self._maps.bind_flakes(flakes, m + 7, m + 8)  # a mesh's glass and chrome read the glint map too
        elif mesh is not None:  # a mesh's glass and chrome: the sharpest lobe map
            self._lobes[int(np.argmax(np.asarray(self.basis.exponents)[self._order]))].use(m + 7)
        if aniso_uniforms:
            self._aniso[aniso_uniforms.pop("_key")][0].use(m + 9)
            uniforms.update(aniso_uniforms)
        uniforms["_wa"], uniforms["_wk"] = w_a, w_k
        if coat is not None and self.diffuse == "sh":
            uniforms["_sh_coat"] = sh_diffuse_matrix(self.basis.sh, coat)
        return uniforms, mw, m

    @property
    def shadow_redraws(self) -> int:
        """How many times the shadow or ambient-occlusion maps were drawn (they are redrawn only when the
        mesh, the environment's turn or the ground change, never for a camera move)."""
        return max(self._frame_shadows.version, 0)

    def _ground_map(self, uniforms: dict, mw: list, occ: np.ndarray, n_occ: int, m: int, shadow: tuple = ()):
        """The ground's radiance per unit albedo over the disc's square (GROUND_MAP² texels, linear), baked
        by ``ground_radiance`` of shaders/render.frag.glsl when the ground, its occluders or the
        environment's turn change; the frame then looks it up once per ground pixel (it depends on the
        ground point only: a Lambertian ground)."""
        key = (
            occ[:n_occ].tobytes(),
            uniforms["u_ground_y"],
            uniforms["u_ground_c"],
            uniforms["u_ground_radius"],
            uniforms["u_rot"],
            shadow[:2],
            self._frame_shadows.version if shadow else -1,
        )
        tex, target, stale = self._passes.ground_target(key, self._half_float, GROUND_MAP)
        if not stale:
            return tex
        prog, vao = self._passes.program(
            "sphere", True, "ground", (0, 1, 0), n_occ=n_occ, shadow=(*shadow[:2], False) if shadow else ()
        )
        self._set_uniforms(prog, {**uniforms, "u_size": (float(GROUND_MAP),) * 2}, mw, occ, m)
        target.use()
        vao.render(mode=self.ctx.TRIANGLES, vertices=3)
        return tex

    def _set_uniforms(self, prog, uniforms: dict, mw: list, occ: np.ndarray, m: int) -> None:
        set_uniforms(prog, uniforms, mw, occ, m, combined=self.combined, lights=self._lights, sh=self._sh)

    def render(
        self,
        scene,
        paints,
        exposure_ev: float = 0.0,
        curve: str = "aces",
        coat: ClearCoat | None = None,
        flakes: FlakeLayer | None = None,
        anisotropy: Anisotropy | None = None,
        anisotropic_samples: int | None = None,
    ):
        """8-bit sRGB frame (H, W, 3) uint8 (a view of the RGBA read-back, the driver's fast path).

        *flakes*: the paints' flake layer (sparkle, ``station.render.flakes``); the level of detail's
        choice is in :attr:`last_flakes`. *anisotropy*, *anisotropic_samples*: see the class doc."""
        fbo = self._draw(
            scene,
            paints,
            False,
            exposure_ev,
            curve,
            coat,
            flakes=flakes,
            anisotropy=anisotropy,
            anisotropic_samples=anisotropic_samples,
        )
        return self._read(fbo, False)

    def _read(self, fbo, linear: bool) -> np.ndarray:
        """The W × H frame of *fbo*, row 0 at the top: float32 radiance (H, W, 3) when *linear*, else a
        uint8 (H, W, 3) view of the RGBA read-back (the driver's fast path)."""
        if linear:
            data = np.frombuffer(fbo.read(components=3, dtype="f4", alignment=1), np.float32)
            return data.reshape(self.height, self.width, 3)[::-1].copy()
        data = np.frombuffer(fbo.read(components=4, alignment=4), np.uint8)
        return data.reshape(self.height, self.width, 4)[::-1, :, :3]

    def draw(
        self,
        scene,
        paints,
        exposure_ev: float = 0.0,
        curve: str = "aces",
        coat: ClearCoat | None = None,
        flakes: FlakeLayer | None = None,
        target=None,
        anisotropy: Anisotropy | None = None,
        anisotropic_samples: int | None = None,
        mesh=None,
    ):
        """Render the 8-bit display frame into this renderer's framebuffer and return it (no read-back:
        a caller on the same context blits it, e.g. ``ctx.copy_framebuffer(screen, fbo)``; row 0 is the
        bottom row, GL's convention). *target*: a framebuffer of this context and of this renderer's
        size (e.g. a widget's, ``ctx.detect_framebuffer``) drawn into instead, which saves the blit.
        *mesh*: a :class:`station.render.meshes.Mesh` drawn instead of the scene's shape, seen by the
        scene's camera on its stage (as :meth:`render_mesh`; drawn with a depth buffer of its own, then
        blitted into *target*)."""
        return self._draw(
            scene,
            paints,
            False,
            exposure_ev,
            curve,
            coat,
            flakes=flakes,
            target=target,
            mesh=mesh,
            anisotropy=anisotropy,
            anisotropic_samples=anisotropic_samples,
        )

    def render_linear(
        self,
        scene,
        paints,
        coat: ClearCoat | None = None,
        flakes: FlakeLayer | None = None,
        anisotropy: Anisotropy | None = None,
        anisotropic_samples: int | None = None,
    ):
        """Linear sRGB radiance (H, W, 3) float32 (*anisotropy*, *anisotropic_samples*: the class doc)."""
        fbo = self._draw(
            scene,
            paints,
            True,
            0.0,
            "clip",
            coat,
            flakes=flakes,
            anisotropy=anisotropy,
            anisotropic_samples=anisotropic_samples,
        )
        return self._read(fbo, True)

    def render_mesh(
        self,
        mesh,
        paints,
        camera=None,
        stage=None,
        coat: ClearCoat | None = None,
        exposure_ev: float = 0.0,
        curve: str = "aces",
        linear: bool = False,
        flakes: FlakeLayer | None = None,
        anisotropy: Anisotropy | None = None,
        anisotropic_samples: int | None = None,
    ):
        """A :class:`station.render.meshes.Mesh` rasterised and shaded with the same equations as the
        shapes (paint 0 at x < 0, paint 1 at x >= 0, neutral parts grey) on *stage* (ground at the mesh's
        floor, contact shadow from its sphere proxies), seen by *camera* (default MESH_CAMERA).
        8-bit sRGB (H, W, 3), or linear float32 radiance with ``linear=True``; row 0 at the top.
        *anisotropy*, *anisotropic_samples*: the class doc (the principal direction is world +x rotated
        by the direction angle, e.g. along the car body)."""
        from station.render.meshes import MESH_CAMERA

        scene = Scene("sphere", camera=camera or MESH_CAMERA, stage=stage)
        fbo = self._draw(
            scene,
            paints,
            linear,
            exposure_ev,
            curve,
            coat,
            mesh=mesh,
            flakes=flakes,
            anisotropy=anisotropy,
            anisotropic_samples=anisotropic_samples,
        )
        return self._read(fbo, linear)

    def shadow_probe(
        self,
        mesh,
        paints,
        camera=None,
        stage=None,
        size: int = 512,
        shape: str = "sphere",
        misalignment_deg: float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Diagnostics of the frame's shadows: :func:`station.render.gl_frame_shadows.probe_shadows`."""
        from station.render.gl_frame_shadows import probe_shadows

        return probe_shadows(self, mesh, paints, camera, stage, size, shape, misalignment_deg)

    def release(self) -> None:
        """Free textures, programs, targets (and the context if this object created it)."""
        self._mesh.release()
        self.targets.release()
        self._passes.release()
        self._maps.release()
        objs = [*self._lobes, self._diffuse_tex, self._horizon_tex]
        objs += [tex for tex, *_ in self._aniso.values()]
        self._narrow_atlas.release()
        self._frame_shadows.release()
        for obj in objs:
            obj.release()
        self._aniso.clear()
        if self._own_ctx:
            self.ctx.release()

    close = release  # ``with GLRenderer(...) as gl:`` releases it on the way out (station.closing.Closing)
