"""OpenGL (moderngl) side of the renderer: the GL renderer.

Every GL object is created from a context made by
:func:`station.render.gl_context.create_gl_context` (a headless EGL context: Mesa llvmpipe on
CPU-only machines, the GPU driver where one exists) and released explicitly; :class:`GLRenderer` is
a context manager. The context factory and shader loader live in :mod:`station.render.gl_context`
and are re-exported here for callers that import them from this module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from station.model.anisotropy import Anisotropy
from station.model.flakes import FlakeLayer
from station.model.gloss import ClearCoat
from station.render import anisotropy as an
from station.render.errors import RenderInputError
from station.render.flakes import (
    CELL_PIXELS,
    FlakeChoice,
    flake_lod,
    flake_mean_cube,
    flake_tint,
    flake_uniforms,
)
from station.render.gl_context import (
    GL_TEXTURE_CUBE_MAP_SEAMLESS,
    SHADER_DIR,
    build_program,
    create_gl_context,
    gl_available,
    load_shader,
)
from station.render.gl_targets import FrameTargets
from station.render.lobes import COSINE_SG_SHARPNESS
from station.render.numpy_renderer import (
    BACKGROUND,
    HORIZON_MAX_EXPONENT,
    check_paints,
    check_size,
    horizon_table,
)
from station.render.prefilter import WIDE_EXPONENT
from station.render.sh import sh_diffuse_matrix
from station.render.shapes import GROUNDS, OCCLUDERS, SHAPE_INDEX, Scene
from station.render.stage import MAX_OCCLUDERS, PENUMBRA_DEG, backdrop_lobe, lookup_matrix
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


class GLRenderer:
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
    the gloss terms per pixel by Schlick's Fresnel (as ``numpy_renderer`` does); None: the thesis's model.

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
    ) -> None:
        import moderngl  # lazily: importing this module needs no GL stack

        check_size(width, height)
        if diffuse not in ("cube", "sh"):
            raise RenderInputError("diffuse", "cube | sh", diffuse)
        self.basis = basis
        self.width, self.height = int(width), int(height)
        self.diffuse = diffuse
        self._own_ctx = ctx is None
        self.ctx = create_gl_context() if ctx is None else ctx
        dtype, np_dtype = ("f2", np.float16) if half_float else ("f4", np.float32)

        def cube_texture(cube):
            s = cube.shape[1]
            tex = self.ctx.texture_cube(
                (s, s), 3, np.ascontiguousarray(cube, dtype=np_dtype).tobytes(), dtype=dtype
            )
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            return tex

        self.combined = combined
        self._combined: tuple[bytes, list] | None = None
        self._combine: tuple | None = None  # (framebuffer, program, vertex array, [gloss, dd]) of the atlas
        self._ground: tuple | None = None  # (key, texture, framebuffer) of the baked ground map
        self._half_float = half_float
        self._atlas_face = max(c.shape[1] for c in basis.cubes)
        # Lobes in binding order: the wide ones (horizon table) first, so the shader loops over a prefix.
        has_lights = basis.lights is not None and any(basis.wide)
        wide = [
            int((horizon != "none" and e < HORIZON_MAX_EXPONENT) or (has_lights and basis.wide[i]))
            for i, e in enumerate(basis.exponents)
        ]
        self._wide_exponent = WIDE_EXPONENT
        self._horizon = horizon
        self._lights = basis.lights if has_lights else None
        self._order = np.array(
            [i for i in range(len(wide)) if wide[i]] + [i for i in range(len(wide)) if not wide[i]]
        )
        self._n_wide = int(sum(wide))
        self._wide = np.array(wide, np.int32)
        self._lobes = [cube_texture(basis.cubes[i]) for i in self._order]
        self._diffuse_tex = cube_texture(basis.diffuse)
        self._horizon_tex = self._horizon_texture(basis.exponents, horizon)
        self._sh = sh_diffuse_matrix(basis.sh)
        self._programs: dict[
            tuple[str, bool, str, tuple[int, ...], tuple[int, int, int], int, int], tuple
        ] = {}
        self._mesh: tuple | None = None
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
        self._flake_means: dict[float, Any] = {}  # spread → mean map texture (_flake_mean)

    def _horizon_texture(self, exponents, horizon: str):
        """The horizon table of the bound lobes as an RGBA texture (sets ``_horizon_n``, its row length)."""
        import moderngl

        table = horizon_table(exponents, horizon)[self._order]  # (m, N, 2): rows = bound lobes
        self._horizon_n = table.shape[1]
        # Two lobes per RGBA row (lobe 2k in .rg, 2k+1 in .ba): one lookup serves a pair of wide lobes.
        pairs = np.zeros(((table.shape[0] + 1) // 2, table.shape[1], 4), np.float32)
        for i in range(table.shape[0]):
            pairs[i // 2, :, 2 * (i % 2) : 2 * (i % 2) + 2] = table[i]
        tex = self.ctx.texture(
            (table.shape[1], pairs.shape[0]), 4, np.ascontiguousarray(pairs).tobytes(), dtype="f4"
        )
        tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
        tex.repeat_x = tex.repeat_y = False
        return tex

    def _program(
        self,
        shape: str,
        linear: bool,
        kind: str = "shape",
        features: tuple[int, ...] = (0, 0, 0),
        terms: tuple[int, int, int] = (-1, 1, 0),
        n_occ: int = 0,
        curve: int = 0,
    ):
        """Program for a ray-cast *shape* (kind "shape"), the stage alone ("stage") or a mesh ("mesh");
        *features* = (coat, stage bits, flakes[, anisotropy]) compiled in (0/1 each; the stage's bits: 1 a
        stage, 2 its backdrop, 4 its ground, 8 the backdrop lobe's lights); *terms* = (bit mask of the
        wide lobes whose gloss weight is non-zero, whether a narrow lobe's directionally diffuse weight
        is, whether the aspecular fall-off is shaded), see :meth:`_terms`; *n_occ*: the ground's sphere
        occluders (0 without a stage), compiled in with the light count so the stage's loops unroll;
        *curve*: the tone curve's index in CURVES (8-bit output)."""
        key = (shape, linear, kind, features, terms, n_occ, curve)
        if key not in self._programs:
            from station.render.meshes import NEUTRAL_ALBEDO

            defines = {
                "SHAPE": SHAPE_INDEX[shape],
                "MESH": int(kind == "mesh"),
                "NO_SHAPE": int(kind in ("stage", "ground")),
                "BAKE_GROUND": int(kind == "ground"),
                "WIDE_GLOSS_MASK": terms[0],
                "NARROW_DD": terms[1],
                "HAS_FALL_OFF": terms[2],
                "N_OCC": n_occ,
                "CURVE": curve,
                "HAS_COAT": features[0],
                "HAS_STAGE": int(features[1] != 0),
                "STAGE_BACKDROP": features[1] >> 1 & 1,
                "STAGE_GROUND": features[1] >> 2 & 1,
                "BACKDROP_LIGHTS": features[1] >> 3 & 1,
                "HAS_FLAKES": features[2],
                **({"HAS_ANISO": 1} if len(features) > 3 and features[3] else {}),
                "NEUTRAL_ALBEDO": f"{NEUTRAL_ALBEDO:.4f}",
                "PENUMBRA_DEG": f"{PENUMBRA_DEG:.4f}",
                "FLAKE_CELL_PIXELS": f"{CELL_PIXELS:.4f}",
                "N_LOBES": len(self._lobes),
                "OUTPUT_LINEAR": int(linear),
                "DIFFUSE_SH": int(self.diffuse == "sh"),
                "COMBINED": int(self.combined),
                "HORIZON_N": self._horizon_n,
                "ATLAS_FACE": self._atlas_face,
                "N_WIDE": self._n_wide,
                "MAX_LIGHTS": max(1, self._lights.count if self._lights is not None else 1),
                # The lights and exponents are fixed per renderer: compiled in as constants, so the
                # lobe and light loops unroll with constant indices (llvmpipe gathers a uniform
                # array indexed by a loop counter per pixel).
                "N_LIGHTS": self._lights.count if self._lights is not None else 0,
                "LOBE_EXPONENTS": ", ".join(
                    f"{float(e):.9g}" for e in np.asarray(self.basis.exponents)[self._order]
                ),
                "WIDE_EXPONENT": f"{self._wide_exponent:.1f}",
                "BENT_DD": int(self._horizon == "lut"),
                "COSINE_SG": f"{COSINE_SG_SHARPNESS:.4f}",
            }
            vert = "mesh.vert.glsl" if kind == "mesh" else "fullscreen.vert.glsl"
            prog = build_program(self.ctx, vert, "render.frag.glsl", defines)
            self._programs[key] = (prog, None if kind == "mesh" else self.ctx.vertex_array(prog, []))
        return self._programs[key]

    def _flake_mean(self, flakes: FlakeLayer):
        """The flakes' mean map C_E for this layer's spread (:func:`station.render.flakes.flake_mean_cube`),
        uploaded once per spread."""
        import moderngl

        key = round(flakes.spread_deg, 6)
        if key not in self._flake_means:
            cube = flake_mean_cube(self.basis, flakes)
            tex = self.ctx.texture_cube(
                (cube.shape[1],) * 2, 3, np.ascontiguousarray(cube).tobytes(), dtype="f4"
            )
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            self._flake_means[key] = tex
        return self._flake_means[key]

    def _combined_atlas(self, pair) -> list:
        """[gloss, dd] atlas textures of both paints' narrow lobes (shaders/combine.frag.glsl; rebuilt on
        the GPU when the weights change, never read back)."""
        mw = [self._bound_weights(w) for w in pair]
        key = b"".join(np.concatenate([w[1].ravel(), w[2]]).astype(np.float32).tobytes() for w in mw)
        if self._combined is not None and self._combined[0] == key:
            return self._combined[1]
        m = len(self._lobes)
        size = self._atlas_face
        combine = self._combine
        if combine is None:
            import moderngl

            dtype = "f2" if self._half_float else "f4"
            atlas = [self.ctx.texture((size + 2, 12 * (size + 2)), 4, dtype=dtype) for _ in range(2)]
            for tex in atlas:
                tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
                tex.repeat_x = tex.repeat_y = False
            prog = build_program(self.ctx, "fullscreen.vert.glsl", "combine.frag.glsl", {"N_LOBES": m})
            fbo = self.ctx.framebuffer(color_attachments=atlas)
            combine = self._combine = (fbo, prog, self.ctx.vertex_array(prog, []), atlas)
        fbo, prog, vao, atlas = combine
        fbo.use()
        for unit, tex in enumerate(self._lobes):
            tex.use(unit)
        prog["u_lobes"].value = list(range(m)) if m > 1 else 0
        prog["u_size"].value = size
        narrow = (self._wide[self._order] == 0).astype(np.float32)
        # wide lobes are looked up per pixel with their horizon factors
        prog["u_wg"].write(np.concatenate([w[2] * narrow for w in mw]).astype(np.float32).tobytes())
        prog["u_wdd"].write(np.concatenate([w[1] * narrow[:, None] for w in mw]).astype(np.float32).tobytes())
        vao.render(mode=self.ctx.TRIANGLES, vertices=3)
        self._combined = (key, atlas)
        return atlas

    def _terms(self, pair) -> tuple[int, int, int]:
        """Which weight groups of these paints are non-zero: (bit i set when wide lobe i has a gloss
        weight in either paint, 1 when a narrow lobe has a directionally diffuse weight, 1 when either
        paint has an aspecular fall-off K_A and the horizon tables are on). A term whose weights are all
        exactly zero adds nothing, so its lookups are compiled out: a typical effect paint has its gloss
        in the narrow lobes and its colour travel in the wide ones (3 of 8 lookups). Without the
        combined maps every lobe is looked up (mask -1)."""
        fall_off = int(self._horizon != "none" and any(w.has_fall_off for w in pair))
        if not self.combined:
            return (-1, 1, fall_off)
        mw = [self._bound_weights(w) for w in pair]
        wide = self._wide[self._order] != 0
        mask = 0
        for i in np.nonzero(wide)[0]:
            if any(w[2][i] > 0.0 for w in mw):
                mask |= 1 << int(i)
        narrow_dd = int(any(np.any(w[1][~wide] > 0.0) for w in mw))
        return (mask, narrow_dd, fall_off)

    def _lights_taken_out(self, lobe: int) -> bool:
        """Whether the extracted lights were taken out of basis lobe *lobe*'s map (so a lookup of it adds
        them back exactly)."""
        return self._lights is not None and bool(self.basis.wide) and bool(self.basis.wide[lobe])

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
    ):
        """One frame into *target* (default this renderer's framebuffer): the frame's features and
        programs (:meth:`_frame_programs`), textures bound and uniforms set (:meth:`_frame_uniforms`), then
        the shape's full-screen pass, or the stage pass and the rasterised mesh."""
        pair = check_paints(self.basis, paints)
        self.last_flakes = flake_lod(flakes, scene.view_camera, self.targets.shade_size[1])
        if not linear:
            check_curve(curve)
        pair, passes, aniso_uniforms, occluders, n_occ = self._frame_programs(
            scene,
            pair,
            linear,
            0 if linear else CURVES.index(curve),
            coat,
            mesh,
            anisotropy,
            anisotropic_samples,
            self.last_flakes.on,
        )
        own = target is None or self.targets.side > 1
        fbo = self.targets.draw_target(linear, depth=mesh is not None) if own else target
        fbo.use()
        occ = np.zeros((MAX_OCCLUDERS, 4), np.float32)
        occ[: len(occluders)] = occluders
        uniforms, mw, m = self._frame_uniforms(scene, pair, fbo, coat, mesh, flakes, aniso_uniforms)
        if not linear:
            uniforms["u_exposure"] = float(2.0**exposure_ev)
        if scene.stage is not None and scene.stage.ground:
            self._ground_map(uniforms, mw, occ, n_occ, m).use(m + 2)
            fbo.use()
            uniforms["u_ground_map"] = m + 2
        for prog, _ in passes:
            self._set_uniforms(prog, uniforms, mw, occ, m)
        if mesh is None:
            passes[0][1].render(mode=self.ctx.TRIANGLES, vertices=3)
        else:
            self._draw_mesh(fbo, passes, mesh)
        if self.targets.side == 1:
            return fbo
        out = target if target is not None else self.targets.output_target(linear)
        return self.targets.resolve(fbo, out)

    def _draw_mesh(self, fbo, passes: list, mesh) -> None:
        """The stage pass (colour only), then *mesh* depth-tested, into *fbo*."""
        fbo.clear(depth=1.0)
        self.ctx.disable(self.ctx.DEPTH_TEST)  # the stage pass writes colour only
        passes[0][1].render(mode=self.ctx.TRIANGLES, vertices=3)
        self.ctx.enable(self.ctx.DEPTH_TEST)
        try:
            self._mesh_vao(mesh, passes[1][0]).render(mode=self.ctx.TRIANGLES)
        finally:
            self.ctx.disable(self.ctx.DEPTH_TEST)

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
    ) -> tuple[list, list, dict, np.ndarray, int]:
        """(paints, passes, anisotropy uniforms, sphere occluders (k, 4), occluders compiled in) of one
        frame: the features compiled in (coat, stage bits, flakes, anisotropy) and the programs."""
        stage = scene.stage
        stage_bits = 0  # bit 0: a stage, 1: its backdrop, 2: its ground, 3: the backdrop lobe's lights
        if stage is not None:
            backdrop = backdrop_lobe(self.basis.exponents, stage.backdrop_blur_deg)
            stage_bits = (
                1
                | int(stage.backdrop) << 1
                | int(stage.ground) << 2
                | int(stage.backdrop and self._lights_taken_out(backdrop)) << 3
            )
        feats: tuple[int, ...] = (int(coat is not None), stage_bits, int(flakes_on))
        aniso_uniforms: dict = {}
        if anisotropy is not None:
            pair, aniso_uniforms = self._anisotropy(pair, anisotropy, anisotropic_samples)
            feats = (*feats, 1)
        else:
            self.last_anisotropy = None
        terms = self._terms(pair)
        if mesh is None:
            occluders = np.asarray(OCCLUDERS[scene.shape], np.float32).reshape(-1, 4)
        else:
            occluders = mesh.occluders().astype(np.float32)
        n_occ = len(occluders) if stage is not None else 0
        if mesh is None:
            passes = [self._program(scene.shape, linear, "shape", feats, terms, n_occ, curve_i)]
        else:
            passes = [
                self._program("sphere", linear, "stage", (0, feats[1], 0), n_occ=n_occ, curve=curve_i),
                self._program("sphere", linear, "mesh", feats, terms, n_occ, curve_i),
            ]
        return pair, passes, aniso_uniforms, occluders, n_occ

    def _frame_uniforms(
        self, scene, pair, fbo, coat, mesh, flakes, aniso_uniforms: dict
    ) -> tuple[dict, list, int]:
        """Bind the frame's textures and return (uniforms, bound weights of the paints, lobe count m)."""
        stage = scene.stage
        backdrop = backdrop_lobe(self.basis.exponents, stage.backdrop_blur_deg if stage is not None else 0.0)
        gx, gy, gz = GROUNDS[scene.shape] if mesh is None else (0.0, mesh.floor_y, 0.0)
        m = len(self._lobes)
        if self.combined:
            cubes = self._combined_atlas(pair)
            fbo.use()
            for unit, tex in enumerate(cubes):
                tex.use(m + unit)
        for unit, tex in enumerate(self._lobes):
            tex.use(unit)
        self._diffuse_tex.use(m + 4)
        self._horizon_tex.use(m + 5)
        self._lobes[int(np.nonzero(self._order == backdrop)[0][0])].use(m + 6)
        uniforms = {
            **scene.view_camera.uniforms(*self.targets.shade_size),
            "u_size": tuple(float(v) for v in self.targets.shade_size),
            "u_misalign": float(np.radians(scene.misalignment_deg)),
            "u_background": (BACKGROUND,) * 3,
            "u_diffuse": m + 4,
            "u_horizon": m + 5,
            "u_coat_f0": coat.f0 if coat is not None else 0.0,
            "u_coat_ref": coat.reference if coat is not None else 1.0,
            "u_rot": tuple(
                float(v) for v in lookup_matrix(stage.rotation_deg if stage else 0.0).T.ravel()
            ),  # column-major
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
            self._flake_mean(flakes).use(m + 8)
        if on or mesh is not None:  # the glints' map; a mesh's glass and chrome
            self._lobes[int(np.nonzero(self._order == int(np.argmax(self.basis.exponents)))[0][0])].use(m + 7)
        if aniso_uniforms:
            self._aniso[aniso_uniforms.pop("_key")][0].use(m + 9)
            uniforms.update(aniso_uniforms)
        mw = [self._bound_weights(w) for w in pair]
        uniforms["_wa"] = [w.fall_off_map_weight() for w in (pair + pair)[:2]]
        return uniforms, mw, m

    def _ground_map(self, uniforms: dict, mw: list, occ: np.ndarray, n_occ: int, m: int):
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
        )
        if self._ground is not None and self._ground[0] == key:
            return self._ground[1]
        if self._ground is None:
            import moderngl

            tex = self.ctx.texture((GROUND_MAP, GROUND_MAP), 4, dtype="f2" if self._half_float else "f4")
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x = tex.repeat_y = False
            target = self.ctx.framebuffer(color_attachments=[tex])
        else:
            tex, target = self._ground[1], self._ground[2]
        prog, vao = self._program("sphere", True, "ground", (0, 1, 0), n_occ=n_occ)
        self._set_uniforms(prog, {**uniforms, "u_size": (float(GROUND_MAP),) * 2}, mw, occ, m)
        target.use()
        vao.render(mode=self.ctx.TRIANGLES, vertices=3)
        self._ground = (key, tex, target)
        return tex

    def _anisotropy(self, pair, anisotropy: Anisotropy, samples: int | None) -> tuple[list, dict]:
        """Paints with their gloss moved into the anisotropic lobe, and the lobe's uniforms (class doc)."""
        import moderngl

        from station.render.lod import AnisotropyChoice, choose_anisotropic_samples
        from station.render.truth import sphere_pixels
        from station.render.weights import LobeWeights

        if self.anisotropy_energy not in an.ENERGIES:
            raise RenderInputError("anisotropy_energy", " | ".join(an.ENERGIES), self.anisotropy_energy)
        lobe = an.WardLobe.from_design(anisotropy)
        key = (lobe.alpha_x, lobe.alpha_y)
        if key not in self._aniso:
            table = an.albedo_table(lobe)
            tex = self.ctx.texture((table.shape[1], table.shape[0]), 1, table.tobytes(), dtype="f4")
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x = tex.repeat_y = False
            w = an.fit_isotropic(self.basis.exponents, lobe.alpha_x)
            self._aniso[key] = (tex, (w / w.sum())[self._order], {})
        tex, w_bound, choices = self._aniso[key]
        if samples is not None:
            an.sample_offsets(lobe, samples)  # validates
            choice = AnisotropyChoice(
                samples, float("nan"), float("nan"), f"{samples} anisotropic samples (given)"
            )
        else:
            ck = (float(self.anisotropy_tolerance_de), self.anisotropy_energy, lobe.tangent)
            if ck not in choices:
                choices[ck] = choose_anisotropic_samples(
                    self.basis, lobe, *sphere_pixels(8), ck[0], energy=self.anisotropy_energy
                )
            choice = choices[ck]
        self.last_anisotropy = choice
        ps = [float(w.map_weights()[2].sum()) for w in pair]
        pair = [LobeWeights(w.exponents, w.k_d, w.k_dd, np.zeros_like(w.k_g), w.k_a) for w in pair]
        uniforms = {
            "_key": key,
            "u_aniso_samples": int(choice.samples) if lobe.spread > 0 else 1,
            "u_aniso_spread": lobe.spread,
            "u_aniso_hint": tuple(float(c) for c in lobe.tangent),
            "u_aniso_albedo": len(self._lobes) + 9,
            "u_aniso_cos_min": an.ALBEDO_COS_MIN,
            "u_aniso_ward_energy": int(self.anisotropy_energy == "ward"),
            "_aniso_w": w_bound,
            "_aniso_ps": (ps + ps)[:2],
        }
        return pair, uniforms

    def _mesh_vao(self, mesh, prog):
        """Vertex array of *mesh* for *prog* (buffers uploaded once per mesh and program)."""
        key = (id(mesh), id(prog))
        if self._mesh is None or self._mesh[0] != key:
            self._release_mesh()
            vbo = self.ctx.buffer(
                np.concatenate([mesh.positions, mesh.normals, mesh.painted[:, None]], axis=1)
                .astype(np.float32)
                .tobytes()
            )
            ibo = self.ctx.buffer(mesh.faces.astype(np.uint32).tobytes())
            vao = self.ctx.vertex_array(
                prog,
                [(vbo, "3f 3f 1f", "in_pos", "in_normal", "in_painted")],
                index_buffer=ibo,
                index_element_size=4,
            )
            self._mesh = (key, mesh, vbo, ibo, vao)
        return self._mesh[4]

    def _release_mesh(self) -> None:
        if self._mesh is not None:
            for obj in self._mesh[2:]:
                obj.release()
            self._mesh = None

    def _set_uniforms(self, prog, uniforms: dict, mw: list, occ: np.ndarray, m: int) -> None:
        for name, value in uniforms.items():
            if name in prog:
                prog[name].value = value
        if "u_wd" in prog:
            prog["u_wd"].write(np.array([w[0] for w in mw], np.float32).tobytes())
        if self.combined:
            for unit, name in enumerate(("u_gloss", "u_dd")):
                if name in prog:
                    prog[name].value = m + unit
        # The compiler trims uniform arrays to the entries the shader can reach (N_WIDE when combined).
        if "u_lobes" in prog:
            n = prog["u_lobes"].array_length
            prog["u_lobes"].value = list(range(n)) if n > 1 else 0
        lights = self._lights
        if lights is not None and lights.count:  # the compiler drops what a program never reads
            for name, values in (("u_light_dir", lights.directions), ("u_light_flux", lights.flux)):
                if name in prog:
                    prog[name].write(values.astype(np.float32).tobytes())
        for name, part in (("u_wdd", 1), ("u_wg", 2)):
            if name in prog:
                n = prog[name].array_length
                prog[name].write(np.concatenate([w[part] for w in mw]).astype(np.float32)[:n].tobytes())
        if "u_aniso_w" in prog:
            prog["u_aniso_w"].write(np.asarray(uniforms["_aniso_w"], np.float32).tobytes())
            prog["u_aniso_ps"].write(np.asarray(uniforms["_aniso_ps"], np.float32).tobytes())
        if "u_flake_tint" in prog:
            prog["u_flake_tint"].write(np.array([flake_tint(w[1]) for w in mw], np.float32).tobytes())
        if "u_wa" in prog:
            prog["u_wa"].write(np.asarray(uniforms["_wa"], np.float32).tobytes())
        if "u_occ" in prog:
            prog["u_occ"].write(occ[: prog["u_occ"].array_length].tobytes())
        if "u_sh" in prog:
            prog["u_sh"].write(self._sh.tobytes())

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
    ):
        """Render the 8-bit display frame into this renderer's framebuffer and return it (no read-back:
        a caller on the same context blits it, e.g. ``ctx.copy_framebuffer(screen, fbo)``; row 0 is the
        bottom row, GL's convention). *target*: a framebuffer of this context and of this renderer's
        size (e.g. a widget's, ``ctx.detect_framebuffer``) drawn into instead, which saves the blit; not
        for meshes (no depth buffer is assumed)."""
        return self._draw(
            scene,
            paints,
            False,
            exposure_ev,
            curve,
            coat,
            flakes=flakes,
            target=target,
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
        data = np.frombuffer(fbo.read(components=3, dtype="f4", alignment=1), np.float32)
        return data.reshape(self.height, self.width, 3)[::-1].copy()

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
        if linear:
            data = np.frombuffer(fbo.read(components=3, dtype="f4", alignment=1), np.float32)
            return data.reshape(self.height, self.width, 3)[::-1].copy()
        data = np.frombuffer(fbo.read(components=4, alignment=4), np.uint8)
        return data.reshape(self.height, self.width, 4)[::-1, :, :3]

    def release(self) -> None:
        """Free textures, programs, targets (and the context if this object created it)."""
        self._release_mesh()
        for prog, vao in self._programs.values():
            if vao is not None:
                vao.release()
            prog.release()
        self.targets.release()
        for tex in [
            *self._lobes,
            self._diffuse_tex,
            self._horizon_tex,
        ]:
            tex.release()
        for tex, *_ in self._aniso.values():
            tex.release()
        for tex in self._flake_means.values():
            tex.release()
        self._flake_means.clear()
        self._aniso.clear()
        if self._combine is not None:
            for obj in (*self._combine[:3], *self._combine[3]):
                obj.release()
            self._combine = None
        if self._ground is not None:
            self._ground[2].release()
            self._ground[1].release()
            self._ground = None
        self._combined = None
        self._programs.clear()
        if self._own_ctx:
            self.ctx.release()

    def __enter__(self) -> GLRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()
