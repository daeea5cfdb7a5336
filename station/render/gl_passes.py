"""The GL renderer's programs and passes (:class:`FramePasses`): one program per frame kind, built once
(the defines of :func:`station.render.gl_programs.frame_defines`), and the draw of a frame's passes — a
ray-cast shape's full-screen pass or its footprint passes (:mod:`station.render.footprint`: the paint
program over the shape's polygon, the background around it, the sphere's inside without the background
code), or a rasterised mesh: its depth first, then the stage where it is not and its program where it is,
each pixel shaded once."""

from __future__ import annotations

from typing import Any

import numpy as np

from station.render import gl_textures as tx
from station.render.errors import RenderError, RenderInputError
from station.render.footprint import MARGIN_PX, footprint_triangles, shape_footprint, sphere_radius_px
from station.render.gl_context import build_program
from station.render.gl_programs import MESH_KINDS, frame_defines
from station.render.gl_shadows import shadow_defines

__all__ = [
    "COARSE_FACTORS",
    "COARSE_MIN_NDV",
    "COARSE_SCALE",
    "FOOTPRINT_VERTICES",
    "FramePasses",
    "coarse_factor",
    "coarse_inner_margin_px",
    "sphere_coarse_factor",
]

#: Vertices the footprint buffer holds (the shape's polygon fan and the sectors around it).
FOOTPRINT_VERTICES = 2048
#: The coarse pass's pixel is this many frame pixels on a side, the larger first: the smooth terms of the
#: paint (the wide lobes and their exact lights, ``smooth_terms`` of shaders/render.frag.glsl) are shaded at
#: 1/k² of the inside's fragments and read back bilinearly (:func:`coarse_factor` picks k per frame).
COARSE_FACTORS = (4, 2)
#: Calibration of :func:`coarse_factor`: the largest k · √E / R allowed, E the sharpest exponent among the
#: smooth terms' lobes and R the sphere's radius on screen (pixels). Set from ``bench.coarse``'s calibration
#: set (two environments, three sizes, four wide exponents, k 2 and 4): every frame with x below 0.106 stays
#: within 0.1 ΔE00 of the per-pixel frame, the first above it does not; rounded down. Checked on held-out
#: frames by tests/render/test_coarse_smooth.py.
COARSE_SCALE = 0.1


def coarse_factor(radius_px: float, sharpest: float) -> int:
    """The coarse pass's factor k for a sphere *radius_px* pixels wide on screen whose smooth terms' sharpest
    lobe has exponent *sharpest*: the largest of COARSE_FACTORS with k √E / R <= COARSE_SCALE, 0 for none
    (every fragment shades them). The terms vary over about R / (2 √E) pixels (a lobe of exponent E is
    1/√E radians wide about the reflection, which turns twice as fast as the normal)."""
    for k in COARSE_FACTORS:
        if k * sharpest**0.5 <= COARSE_SCALE * radius_px:
            return k
    return 0


#: The inside of a coarse frame keeps to the part of the sphere seen at N·V at least this: toward the rim the
#: normal turns ever faster across the screen (1 / (R N·V) radians a pixel), and the band outside is shaded per
#: pixel (about 3 % of the sphere's radius).
COARSE_MIN_NDV = 0.25


def sphere_coarse_factor(scene: Any, weights: list, sharpest: float, height: int) -> int:
    """The coarse factor of a frame of *scene* (:func:`coarse_factor`; 0: none) whose paints have the bound
    weights *weights* ((w_d, w_dd, w_g) each) and whose smooth terms' sharpest lobe has exponent *sharpest*,
    shaded *height* pixels high: only the sphere's footprint has an inside, and only paints with the same
    wide-lobe weights have one set of smooth terms (two would blur the seam between them). The sphere's
    radius on screen is the unit sphere's about the origin seen on the view's axis."""
    if scene.shape != "sphere":
        return 0
    if len(weights) > 1:
        (_, dd0, g0), (_, dd1, g1) = weights[:2]
        if not (np.array_equal(dd0, dd1) and np.array_equal(g0, g1)):
            return 0
    radius_px = sphere_radius_px(scene.view_camera, height)
    return coarse_factor(radius_px, sharpest) if radius_px > 0.0 else 0


def coarse_inner_margin_px(factor: int) -> float:
    """How far (pixels) the inside lies within the silhouette for a coarse pass of *factor*: a bilinear read
    takes coarse samples up to *factor* pixels away along each axis, and every one of them must hit."""
    return MARGIN_PX + factor * 2.0**0.5 + 0.5


class FramePasses:
    """The programs of one renderer on *ctx* (*defines*: the renderer's own, ``renderer_defines``) and
    the footprint buffer of its ray-cast shapes."""

    def __init__(self, ctx: Any, defines: dict) -> None:
        self.ctx = ctx
        self._defines = defines
        self._programs: dict[tuple, tuple] = {}  # (program's arguments) → (program, vertex array)
        self._footprint_buf = ctx.buffer(reserve=FOOTPRINT_VERTICES * 8)
        self._footprint_counts = (0, 0, 0)  # vertices inside, in the ring, outside (in buffer order)
        self._ground: tuple | None = None  # (key, texture, framebuffer) of the baked ground map
        # (gloss texture, rest texture, framebuffer, size) of the coarse pass
        self._coarse: tuple | None = None
        # the sharpest exponent of the smooth terms' lobes (the wide ones, all of them uncombined; 0: none)
        exps = [float(e) for e in str(defines["LOBE_EXPONENTS"]).split(",")]
        smooth = exps[: int(defines["N_WIDE"])] if defines["COMBINED"] else exps
        self._smooth_sharpest = max(smooth, default=0.0)

    def program(
        self,
        shape: str,
        linear: bool,
        kind: str = "shape",
        features: tuple[int, ...] = (0, 0, 0),
        terms: tuple[int, int, int] = (-1, 1, 0),
        n_occ: int = 0,
        curve: int = 0,
        shadow: tuple = (),
    ) -> tuple:
        """(program, vertex array) of a kind, built once: the arguments are those of
        :func:`station.render.gl_programs.frame_defines` (*terms*: ``GLRenderer._terms``; *n_occ* is
        compiled in with the light count so the stage's loops unroll); *shadow*: (shadowed light indices,
        ambient occlusion on, probe) of :meth:`station.render.gl_frame_shadows.FrameShadows.key`, () for
        none. A mesh program has no vertex array (the mesh's own is bound)."""
        key = (shape, linear, kind, features, terms, n_occ, curve, shadow)
        if key not in self._programs:
            defines = {**self._defines, **frame_defines(shape, linear, kind, features, terms, n_occ, curve)}
            if shadow:
                defines.update(shadow_defines(shadow[0], shadow[1]), SHADOW_PROBE=int(shadow[2]))
            screen = kind in ("footprint", "backdrop", "inside", "inside-smooth", "coarse")
            vert = "screen.vert.glsl" if screen else "fullscreen.vert.glsl"
            if kind in MESH_KINDS:
                vert = "mesh.vert.glsl"
            prog = build_program(self.ctx, vert, "render.frag.glsl", defines)
            if kind in MESH_KINDS:
                vao = None
            elif screen:
                vao = self.ctx.vertex_array(prog, [(self._footprint_buf, "2f", "in_ndc")])
            else:
                vao = self.ctx.vertex_array(prog, [])
            self._programs[key] = (prog, vao)
        return self._programs[key]

    def frame_footprint(
        self, scene: Any, size: tuple[int, int], weights: list, coarse: bool, footprint: bool, probe: bool
    ) -> tuple[Any, int]:
        """(footprint or None, coarse factor k or 0) of a frame of *scene* shaded at *size*, its paints' bound
        weights *weights*: with *coarse*, :func:`sphere_coarse_factor` for the renderer's smooth terms (its
        wide lobes, or all of them uncombined; 0 without any), and the inside then kept to where the coarse
        read is exact enough; with *footprint*, the shape's screen footprint (None: one full-screen pass).
        A shadow *probe* takes neither."""
        coarse, footprint = coarse and not probe, footprint and not probe
        sharpest = self._smooth_sharpest
        k = sphere_coarse_factor(scene, weights, sharpest, size[1]) if coarse and sharpest > 0.0 else 0
        if not footprint:
            return None, k
        margin, ndv = (coarse_inner_margin_px(k), COARSE_MIN_NDV) if k else (MARGIN_PX, 0.0)
        return shape_footprint(scene.shape, scene.view_camera, *size, scene.misalignment_deg, margin, ndv), k

    def shape_passes(
        self,
        shape: str,
        foot: Any,
        linear: bool,
        feats: tuple,
        terms: tuple,
        n_occ: int,
        curve: int,
        shadow: tuple,
        coarse: bool = False,
    ) -> list:
        """The passes of a ray-cast *shape*: with its footprint *foot* (``shape_footprint``) the paint
        program over the polygon, the background program around it and, where the polygon has an inside,
        the paint without the background code; with *foot* None one full-screen paint pass. *coarse*
        (with an inside): the inside reads the smooth terms from a fourth pass, the coarse one
        (:meth:`draw`)."""
        if foot is None:
            return [self.program(shape, linear, "shape", feats, terms, n_occ, curve, shadow)]
        self.upload_footprint(foot)
        passes = [
            self.program(shape, linear, "footprint", feats, terms, n_occ, curve, shadow),
            self.program("sphere", linear, "backdrop", (0, feats[1], 0), n_occ=n_occ, curve=curve),
        ]
        if foot.inner is not None and coarse:
            passes.append(self.program(shape, linear, "inside-smooth", feats, terms, n_occ, curve, shadow))
            passes.append(
                self.program(shape, True, "coarse", (feats[0], feats[1], 0), terms, n_occ, 0, shadow)
            )
        elif foot.inner is not None:
            passes.append(self.program(shape, linear, "inside", feats, terms, n_occ, curve, shadow))
        return passes

    def mesh_passes(
        self, linear: bool, feats: tuple, terms: tuple, n_occ: int, curve: int, shadow: tuple, prepass: bool
    ) -> list:
        """The stage pass (colour only) and the mesh's program for all its triangles; with *prepass*, the
        stage pass, the paint's program, the depth pre-pass (the mesh's vertex program, no colour:
        shaders/shadow_depth.frag.glsl) and the neutral parts' program (:meth:`_draw_mesh`)."""
        stage = self.program("sphere", linear, "stage", (0, feats[1], 0), n_occ=n_occ, curve=curve)
        if not prepass:
            return [stage, self.program("sphere", linear, "mesh", feats, terms, n_occ, curve, shadow)]
        key = ("mesh-depth",)
        if key not in self._programs:
            self._programs[key] = (build_program(self.ctx, "mesh.vert.glsl", "shadow_depth.frag.glsl"), None)
        return [
            stage,
            self.program("sphere", linear, "mesh-paint", feats, terms, n_occ, curve, shadow),
            self._programs[key],
            self.program("sphere", linear, "mesh-parts", feats, terms, n_occ, curve, shadow),
        ]

    def upload_footprint(self, foot: Any) -> None:
        """Write the triangles of the shape's footprint *foot* (inside, ring, outside; NDC) into the
        footprint buffer (:func:`station.render.footprint.footprint_triangles`)."""
        parts = footprint_triangles(foot)
        data = np.concatenate(parts)
        if len(data) > FOOTPRINT_VERTICES:
            raise RenderInputError("footprint", f"<= {FOOTPRINT_VERTICES} vertices", len(data))
        self._footprint_buf.write(data.tobytes())
        self._footprint_counts = (len(parts[0]), len(parts[1]), len(parts[2]))

    def draw(
        self,
        fbo: Any,
        passes: list,
        mesh: Any = None,
        mesh_arrays: Any = None,
        probe: bool = False,
        prepass: bool = True,
    ) -> None:
        """Draw a frame's *passes* into *fbo* (uniforms already set): a mesh (:meth:`_draw_mesh`; *probe*:
        no stage, the background −1); a shape's one pass; or its footprint's passes (the background around
        the polygon, the paint over it, the inside without background code)."""
        if mesh is not None:
            if probe:
                fbo.clear(-1.0, -1.0, -1.0, 1.0, depth=1.0)
            else:
                fbo.clear(depth=1.0)
            self._draw_mesh(fbo, passes, mesh, mesh_arrays, probe, prepass)
        elif len(passes) == 1:
            passes[0][1].render(mode=self.ctx.TRIANGLES, vertices=3)
        else:
            inside, ring, outside = self._footprint_counts
            if len(passes) == 4:  # the smooth terms at the coarse rate first, over the whole polygon
                if self._coarse is None:
                    raise RenderError("the coarse pass drawn before coarse_target made its maps")
                target = self._coarse[2]
                target.use()
                target.clear()
                passes[3][1].render(mode=self.ctx.TRIANGLES, vertices=inside + ring)
                fbo.use()
            passes[1][1].render(mode=self.ctx.TRIANGLES, vertices=outside, first=inside + ring)
            passes[0][1].render(mode=self.ctx.TRIANGLES, vertices=ring, first=inside)
            if inside:
                passes[2][1].render(mode=self.ctx.TRIANGLES, vertices=inside)

    def _draw_mesh(
        self, fbo: Any, passes: list, mesh: Any, mesh_arrays: Any, probe: bool, prepass: bool
    ) -> None:
        """A mesh and its stage (:meth:`mesh_passes`) into *fbo*, its depth cleared to 1: the mesh's depth alone
        first (colour writes off), then the stage where the depth is still 1 (its triangle lies on the far
        plane, shaders/fullscreen.vert.glsl) and the mesh where its depth is the one kept (both tested <=,
        depth writes off): every pixel is shaded once. llvmpipe tests the depth before the fragment program
        and skips blocks it hides, so a part hidden behind another (the cabin behind the glass, a wheel's far
        side) costs nothing. The mesh is drawn in two ranges of its triangles
        (:class:`station.render.gl_textures.MeshArrays`), the paint's with the paint's program and the
        neutral parts' with theirs: llvmpipe runs both sides of a branch, so a program for both made every
        pixel pay for both. Without *prepass*, :meth:`_draw_mesh_plain`. The frame is the same either way
        (the depth test keeps the nearest; the vertex program is ``invariant``), but where two triangles lie
        at the same depth on a pixel: the last of them drawn shows with the pre-pass, the first without."""
        if not prepass:
            self._draw_mesh_plain(passes, mesh, mesh_arrays, probe)
            return
        ctx = self.ctx
        ctx.enable(ctx.DEPTH_TEST)
        try:
            fbo.color_mask = (False, False, False, False)
            mesh_arrays.vao(mesh, passes[2][0]).render(mode=ctx.TRIANGLES)
            fbo.color_mask = (True, True, True, True)
            fbo.depth_mask = False
            ctx.depth_func = "<="
            if not probe:
                passes[0][1].render(mode=ctx.TRIANGLES, vertices=3)
            paint, total = mesh_arrays.paint_indices(mesh), 3 * len(mesh.faces)
            if paint:
                mesh_arrays.vao(mesh, passes[1][0]).render(mode=ctx.TRIANGLES, vertices=paint)
            if total > paint:
                mesh_arrays.vao(mesh, passes[3][0]).render(
                    mode=ctx.TRIANGLES, vertices=total - paint, first=paint
                )
        finally:
            fbo.color_mask = (True, True, True, True)
            fbo.depth_mask = True
            ctx.depth_func = "<"
            ctx.disable(ctx.DEPTH_TEST)

    def _draw_mesh_plain(self, passes: list, mesh: Any, mesh_arrays: Any, probe: bool) -> None:
        """A mesh as before the pre-pass: the stage pass over the whole frame (no depth test), then every
        triangle shaded as it comes by one program for both materials, depth-tested (<): a pixel pays for
        each triangle drawn over it before the nearest, and for the stage under the mesh."""
        ctx = self.ctx
        if not probe:
            passes[0][1].render(mode=ctx.TRIANGLES, vertices=3)
        ctx.enable(ctx.DEPTH_TEST)
        try:
            mesh_arrays.vao(mesh, passes[1][0]).render(mode=ctx.TRIANGLES)
        finally:
            ctx.disable(ctx.DEPTH_TEST)

    def coarse_target(self, size: tuple[int, int]) -> tuple[Any, Any]:
        """(gloss texture, rest texture) of the coarse pass at *size* (RGBA float, bilinear, clamped),
        made once per size; :meth:`draw` draws into them."""
        if self._coarse is None or self._coarse[3] != size:
            self._release_coarse()
            g = tx.colour_texture(self.ctx, size, False)
            dd = tx.colour_texture(self.ctx, size, False)
            self._coarse = (g, dd, self.ctx.framebuffer(color_attachments=[g, dd]), size)
        return self._coarse[0], self._coarse[1]

    def bind_coarse(self, passes: list, shade_size: tuple[int, int], factor: int, unit: int) -> None:
        """Bind the coarse pass's maps of *factor* (made at the shading size *shade_size* over *factor*) to
        texture units *unit* and *unit* + 1 for the inside's program, and give the coarse program its size
        (*passes*: :meth:`shape_passes`'s, uniforms set); nothing for a frame without the coarse pass."""
        if len(passes) != 4 or factor <= 0:
            return
        size = (-(-shade_size[0] // factor), -(-shade_size[1] // factor))
        g_tex, dd_tex = self.coarse_target(size)
        g_tex.use(unit)
        dd_tex.use(unit + 1)
        passes[3][0]["u_size"].value = (float(size[0]), float(size[1]))
        passes[2][0]["u_smooth_g"].value = unit
        passes[2][0]["u_smooth_dd"].value = unit + 1

    def _release_coarse(self) -> None:
        if self._coarse is not None:
            for obj in reversed(self._coarse[:3]):
                obj.release()
            self._coarse = None

    def ground_target(self, key: tuple, half_float: bool, size: int) -> tuple[Any, Any, bool]:
        """(texture, framebuffer, stale) of the baked ground map (size² texels): the map baked for *key*
        (stale False), else the texture to bake it into, reused or made (stale True; it now holds *key*)."""
        if self._ground is not None and self._ground[0] == key:
            return self._ground[1], self._ground[2], False
        if self._ground is None:
            tex = tx.colour_texture(self.ctx, (size, size), half_float)
            target = self.ctx.framebuffer(color_attachments=[tex])
        else:
            tex, target = self._ground[1], self._ground[2]
        self._ground = (key, tex, target)
        return tex, target, True

    def release(self) -> None:
        """Free the programs, their vertex arrays, the footprint buffer and the ground map."""
        for pv in self._programs.values():
            for obj in reversed(pv):
                if obj is not None:
                    obj.release()
        self._programs.clear()
        self._footprint_buf.release()
        self._release_coarse()
        if self._ground is not None:
            self._ground[2].release()
            self._ground[1].release()
            self._ground = None
