"""Textures and buffers of :class:`station.render.gl_renderer.GLRenderer`: the lobe cube maps, the horizon
table, the flakes' mean map, the anisotropic albedo table, the combined lobe and diffuse atlases, the baked
ground map and a mesh's vertex arrays. Each function creates GL objects on *ctx*; the renderer owns and
releases them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from station.render.gl_context import GL_RGB9_E5, build_program


def _linear_clamped(tex: Any) -> Any:
    """*tex* with bilinear filtering and clamped edges."""
    import moderngl

    tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
    tex.repeat_x = tex.repeat_y = False
    return tex


def cube_texture(ctx: Any, cube: np.ndarray, half_float: bool) -> Any:
    """(6, s, s, 3) radiance cube as a bilinear RGB cube texture (half or single float)."""
    import moderngl

    dtype, np_dtype = ("f2", np.float16) if half_float else ("f4", np.float32)
    s = cube.shape[1]
    tex = ctx.texture_cube((s, s), 3, np.ascontiguousarray(cube, dtype=np_dtype).tobytes(), dtype=dtype)
    tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
    return tex


def shared_exponent_cube(ctx: Any, cube: np.ndarray) -> Any:
    """(6, s, s, 3) radiance cube as a bilinear shared-exponent cube texture (GL_RGB9_E5: 32 bits a texel,
    each channel to 2^-9 of the texel's largest, against 48 bits for half floats): llvmpipe fetches a
    32-bit texel in one gather, so a lookup costs less (the flakes' glint and mean maps, which are looked
    up three times per shape pixel and only scaled by the sparkle's weights)."""
    import moderngl

    s = cube.shape[1]
    data = np.ascontiguousarray(cube, dtype=np.float32).tobytes()
    tex = ctx.texture_cube((s, s), 3, data, dtype="f4", internal_format=GL_RGB9_E5)
    tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
    return tex


def horizon_texture(ctx: Any, table: np.ndarray) -> Any:
    """The horizon table (m, N, 2) of the bound lobes as an RGBA float texture of N columns: first
    ⌈m/4⌉ rows of g alone, four lobes a row (lobe 4k+j in component j), then ⌈m/2⌉ rows of (g, h)
    pairs (lobe 2k in .rg, 2k+1 in .ba), so one lookup serves four wide lobes without a gloss weight or a
    pair of wide lobes with one (``horizon_g`` and ``horizon`` of shaders/render.frag.glsl)."""
    m, n = table.shape[0], table.shape[1]
    g_rows = (m + 3) // 4
    rows = np.zeros((g_rows + (m + 1) // 2, n, 4), np.float32)
    for i in range(m):
        rows[i // 4, :, i % 4] = table[i, :, 0]
        rows[g_rows + i // 2, :, 2 * (i % 2) : 2 * (i % 2) + 2] = table[i]
    tex = ctx.texture((n, rows.shape[0]), 4, np.ascontiguousarray(rows).tobytes(), dtype="f4")
    return _linear_clamped(tex)


def table_texture(ctx: Any, table: np.ndarray) -> Any:
    """A 2-D single-channel float table (rows, columns) as a bilinear clamped texture."""
    return _linear_clamped(ctx.texture((table.shape[1], table.shape[0]), 1, table.tobytes(), dtype="f4"))


def colour_texture(ctx: Any, size: tuple[int, int], half_float: bool) -> Any:
    """An empty RGBA float render texture of *size* (bilinear, clamped)."""
    return _linear_clamped(ctx.texture(size, 4, dtype="f2" if half_float else "f4"))


def combine_pass(ctx: Any, face: int, n_lobes: int, half_float: bool) -> tuple:
    """(framebuffer, program, vertex array, [gloss, dd] atlas textures) that sum the narrow lobes of a
    pair of paints into the atlases (``shaders/combine.frag.glsl``; 12 faces of *face* + 2 texels)."""
    atlas = [colour_texture(ctx, (face + 2, 12 * (face + 2)), half_float) for _ in range(2)]
    prog = build_program(ctx, "fullscreen.vert.glsl", "combine.frag.glsl", {"N_LOBES": n_lobes})
    return (ctx.framebuffer(color_attachments=atlas), prog, ctx.vertex_array(prog, []), atlas)


class NarrowAtlas:
    """The [gloss, dd] atlases of both paints' *narrow* (1/0 per bound lobe) *lobes* (:func:`combine_pass`,
    :func:`draw_combined`) on *ctx* at *face* texels a face, redrawn on the GPU only when the paints'
    weights change."""

    def __init__(self, ctx: Any, lobes: list, narrow: np.ndarray, face: int, half_float: bool) -> None:
        self.ctx, self.lobes, self.narrow, self.face, self.half_float = ctx, lobes, narrow, face, half_float
        self._pass: tuple | None = None  # (framebuffer, program, vertex array, [gloss, dd])
        self._key: bytes | None = None

    def atlases(self, mw: list) -> list:
        """[gloss, dd] of the paints' bound weights *mw* (w_D, w_DD, w_G per paint)."""
        key = b"".join(np.concatenate([w[1].ravel(), w[2]]).astype(np.float32).tobytes() for w in mw)
        if self._pass is None:
            self._pass = combine_pass(self.ctx, self.face, len(self.lobes), self.half_float)
        elif self._key == key:
            return self._pass[3]
        self._key = key
        return draw_combined(self.ctx, self._pass, self.lobes, self.face, self.narrow, mw)

    def release(self) -> None:
        """Free the pass and its atlases."""
        if self._pass is not None:
            for obj in [*self._pass[:3], *self._pass[3]]:
                obj.release()
        self._pass = self._key = None


def diffuse_combine_pass(ctx: Any, face: int, half_float: bool) -> tuple:
    """(framebuffer, program, vertex array, atlas texture) that pre-mix both paints' diffuse base under a
    clear coat into one atlas (``shaders/combine_diffuse.frag.glsl``; 12 faces of *face* + 2 texels)."""
    atlas = colour_texture(ctx, (face + 2, 12 * (face + 2)), half_float)
    prog = build_program(ctx, "fullscreen.vert.glsl", "combine_diffuse.frag.glsl", {})
    return (ctx.framebuffer(color_attachments=[atlas]), prog, ctx.vertex_array(prog, []), atlas)


def draw_diffuse_combined(
    ctx: Any, combine: tuple, diffuse: Any, coat_diffuse: Any, face: int, w_plain: list, w_coat: list
) -> Any:
    """Mix the diffuse map *diffuse* and the coat-transmitted one *coat_diffuse* of both paints, weights
    *w_plain* and *w_coat* (two RGB each: pi K_A and pi K_D), into the atlas of *combine*
    (:func:`diffuse_combine_pass`) and return it."""
    fbo, prog, vao, atlas = combine
    fbo.use()
    diffuse.use(0)
    coat_diffuse.use(1)
    prog["u_diffuse"].value = 0
    prog["u_diffuse_coat"].value = 1
    prog["u_size"].value = face
    prog["u_w_plain"].write(np.asarray(w_plain, np.float32).tobytes())
    prog["u_w_coat"].write(np.asarray(w_coat, np.float32).tobytes())
    vao.render(mode=ctx.TRIANGLES, vertices=3)
    return atlas


def mesh_buffers(ctx: Any, mesh: Any) -> tuple[Any, Any, int]:
    """(vertex buffer, index buffer, indices of the paint) of a :class:`station.render.meshes.Mesh`:
    position, normal and the material code per vertex; the triangles of the paint first, then the neutral
    parts', each in the mesh's order. A triangle's material is its last vertex's, as the fragment program
    reads it (``flat``: GL's provoking vertex is the last)."""
    from station.render.meshes import PAINT

    vbo = ctx.buffer(
        np.concatenate([mesh.positions, mesh.normals, mesh.painted[:, None]], axis=1)
        .astype(np.float32)
        .tobytes()
    )
    painted = np.abs(mesh.painted[mesh.faces[:, 2]] - PAINT) < 0.5
    order = np.argsort(~painted, kind="stable")
    ibo = ctx.buffer(np.ascontiguousarray(mesh.faces[order], np.uint32).tobytes())
    return vbo, ibo, 3 * int(painted.sum())


def mesh_vertex_array(ctx: Any, prog: Any, vbo: Any, ibo: Any) -> Any:
    """The vertex array of *prog* over a mesh's buffers (:func:`mesh_buffers`)."""
    return ctx.vertex_array(
        prog,
        [(vbo, "3f 3f 1f", "in_pos", "in_normal", "in_painted")],
        index_buffer=ibo,
        index_element_size=4,
        skip_errors=True,  # a program that reads fewer attributes (the shadow probe, the depth pre-pass)
    )


def draw_combined(ctx: Any, combine: tuple, lobes: list, face: int, narrow: np.ndarray, mw: list) -> list:
    """Sum the *narrow* (1/0 per bound lobe) lobes of both paints' bound weights *mw* into the [gloss,
    dd] atlases of *combine* (:func:`combine_pass`) and return them; the wide lobes are looked up per
    pixel with their horizon factors."""
    fbo, prog, vao, atlas = combine
    fbo.use()
    for unit, tex in enumerate(lobes):
        tex.use(unit)
    prog["u_lobes"].value = list(range(len(lobes))) if len(lobes) > 1 else 0
    prog["u_size"].value = face
    prog["u_wg"].write(np.concatenate([w[2] * narrow for w in mw]).astype(np.float32).tobytes())
    prog["u_wdd"].write(np.concatenate([w[1] * narrow[:, None] for w in mw]).astype(np.float32).tobytes())
    vao.render(mode=ctx.TRIANGLES, vertices=3)
    return atlas


class MeshArrays:
    """The buffers of the last mesh drawn (:func:`mesh_buffers`), uploaded once per mesh, and one vertex array
    over them per program that draws it (the depth pre-pass's, the paint's, the neutral parts')."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self._buffers: tuple | None = None  # (mesh, vbo, ibo, indices of the paint)
        self._vaos: dict[int, tuple] = {}  # id(program) → (program, vertex array)

    def paint_indices(self, mesh: Any) -> int:
        """How many of *mesh*'s indices, from the first, draw the paint's triangles (the rest the neutral
        parts'; :func:`mesh_buffers`)."""
        return int(self._upload(mesh)[3])

    def _upload(self, mesh: Any) -> tuple:
        """(mesh, vertex buffer, index buffer, indices of the paint), uploaded on a new mesh."""
        if self._buffers is None or self._buffers[0] is not mesh:
            self.release()
            self._buffers = (mesh, *mesh_buffers(self.ctx, mesh))
        return self._buffers

    def vao(self, mesh: Any, prog: Any) -> Any:
        """Vertex array of *mesh* for *prog* (the previous mesh's buffers and arrays released on a change).
        The mesh and each program are held with their array, so that neither id can be reused by a new
        object while it is cached (a released program's id taken by a new program drew a stale array)."""
        buffers = self._upload(mesh)
        held = self._vaos.get(id(prog))
        if held is None or held[0] is not prog:
            if held is not None:
                held[1].release()
            held = (prog, mesh_vertex_array(self.ctx, prog, *buffers[1:3]))
            self._vaos[id(prog)] = held
        return held[1]

    def release(self) -> None:
        """Free the buffers and vertex arrays."""
        for _, vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
        if self._buffers is not None:
            for obj in self._buffers[1:3]:
                obj.release()
            self._buffers = None
