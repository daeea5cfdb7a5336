"""The GL renderer's programs and passes (:class:`FramePasses`): one program per frame kind, built once
(the defines of :func:`station.render.gl_programs.frame_defines`), and the draw of a frame's passes — a
ray-cast shape's full-screen pass or its footprint passes (:mod:`station.render.footprint`: the paint
program over the shape's polygon, the background around it, the sphere's inside without the background
code), or the stage pass and a rasterised mesh."""

from __future__ import annotations

from typing import Any

import numpy as np

from station.render import gl_textures as tx
from station.render.errors import RenderInputError
from station.render.footprint import footprint_triangles
from station.render.gl_context import build_program
from station.render.gl_programs import frame_defines
from station.render.gl_shadows import shadow_defines

__all__ = ["FOOTPRINT_VERTICES", "FramePasses"]

#: Vertices the footprint buffer holds (the shape's polygon fan and the sectors around it).
FOOTPRINT_VERTICES = 2048


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
            screen = kind in ("footprint", "backdrop", "inside")
            vert = {"mesh": "mesh.vert.glsl"}.get(
                kind, "screen.vert.glsl" if screen else "fullscreen.vert.glsl"
            )
            prog = build_program(self.ctx, vert, "render.frag.glsl", defines)
            if kind == "mesh":
                vao = None
            elif screen:
                vao = self.ctx.vertex_array(prog, [(self._footprint_buf, "2f", "in_ndc")])
            else:
                vao = self.ctx.vertex_array(prog, [])
            self._programs[key] = (prog, vao)
        return self._programs[key]

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
    ) -> list:
        """The passes of a ray-cast *shape*: with its footprint *foot* (``shape_footprint``) the paint
        program over the polygon, the background program around it and, where the polygon has an inside,
        the paint without the background code; with *foot* None one full-screen paint pass."""
        if foot is None:
            return [self.program(shape, linear, "shape", feats, terms, n_occ, curve, shadow)]
        self.upload_footprint(foot)
        passes = [
            self.program(shape, linear, "footprint", feats, terms, n_occ, curve, shadow),
            self.program("sphere", linear, "backdrop", (0, feats[1], 0), n_occ=n_occ, curve=curve),
        ]
        if foot.inner is not None:
            passes.append(self.program(shape, linear, "inside", feats, terms, n_occ, curve, shadow))
        return passes

    def mesh_passes(
        self, linear: bool, feats: tuple, terms: tuple, n_occ: int, curve: int, shadow: tuple
    ) -> list:
        """The stage pass (colour only) and the mesh's program."""
        return [
            self.program("sphere", linear, "stage", (0, feats[1], 0), n_occ=n_occ, curve=curve),
            self.program("sphere", linear, "mesh", feats, terms, n_occ, curve, shadow),
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
        self, fbo: Any, passes: list, mesh: Any = None, mesh_arrays: Any = None, probe: bool = False
    ) -> None:
        """Draw a frame's *passes* into *fbo* (uniforms already set): a mesh after its stage pass,
        depth-tested (*probe*: no stage, the background −1); a shape's one pass; or its footprint's passes
        (the background around the polygon, the paint over it, the inside without background code)."""
        if mesh is not None:
            fbo.clear(depth=1.0)
            self.ctx.disable(self.ctx.DEPTH_TEST)  # the stage pass writes colour only
            if probe:
                fbo.clear(-1.0, -1.0, -1.0, 1.0, depth=1.0)
            else:
                passes[0][1].render(mode=self.ctx.TRIANGLES, vertices=3)
            self.ctx.enable(self.ctx.DEPTH_TEST)
            try:
                mesh_arrays.vao(mesh, passes[1][0]).render(mode=self.ctx.TRIANGLES)
            finally:
                self.ctx.disable(self.ctx.DEPTH_TEST)
        elif len(passes) == 1:
            passes[0][1].render(mode=self.ctx.TRIANGLES, vertices=3)
        else:
            inside, ring, outside = self._footprint_counts
            passes[1][1].render(mode=self.ctx.TRIANGLES, vertices=outside, first=inside + ring)
            passes[0][1].render(mode=self.ctx.TRIANGLES, vertices=ring, first=inside)
            if inside:
                passes[2][1].render(mode=self.ctx.TRIANGLES, vertices=inside)

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
        if self._ground is not None:
            self._ground[2].release()
            self._ground[1].release()
            self._ground = None
