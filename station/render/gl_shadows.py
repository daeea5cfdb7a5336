"""Shadow maps and ground ambient occlusion of a mesh or a ray-cast shape for the GL renderer
(``shaders/shadows.glsl``).

* **Which lights.** Of the lights taken out of the environment (``PrefilteredBasis.lights``) the
  SHADOW_LIGHTS of largest luminous flux cast shadow maps (:func:`shadow_lights`): the sun, a booth's main
  lamps. The others keep the ground's sphere-proxy sun shadow (``station.render.stage.light_visibility``).
* **Depth pass.** Per shadowed light one depth map of SHADOW_MAP² texels, an orthographic view along the
  light's world direction l fitted to the mesh's bounding box (:func:`ortho_matrix`): the map holds, per
  texel, the depth of the mesh nearest to the light. It is drawn again only when the mesh, the
  environment's turn or the lights change (:class:`ShadowMaps`): an orbit moves the camera, not the
  environment, so orbit frames reuse the maps.
* **Ray-cast shapes.** A shape of ``station.render.shapes`` (:class:`ShapeCaster`) has no triangles: its
  depth pass casts, per texel, the ray from the view's near plane along the view's depth axis at the
  analytic shape with the frame's own ``hit()`` (``shaders/shadow_cast.frag.glsl``) and writes the first
  hit's depth (gl_FragDepth); the maps, their filtering and every lookup are then the mesh's. The box is
  the footprint's bound of the shape (``station.render.footprint.bound_points``). The height maps of the
  ambient occlusion are cast the same way for the closed solids (sphere, cylinder, speed shape); the
  panels and the seam are open sheets that a view from above sees edge-on, so their ground keeps the
  sphere proxies' open sky (:attr:`ShapeCaster.closed`).
* **Ground: percentage-closer soft shadows.** The ground is baked into a map once per stage and light
  (``GLRenderer._ground_map``), so its lookup can afford a full one: a ground point, moved off its surface
  along its normal by NORMAL_OFFSET texels (more at grazing light), is projected into the map; a blocker
  search over the disc that the light of angular radius a (:func:`light_radius_rad`) would cover gives
  the mean blocker depth, the penumbra radius is (receiver − blocker depth) · tan a (at least a texel),
  and the visibility V is the mean of 8 depth comparisons (each a bilinear 2 × 2 comparison) over
  that radius, in [0, 1]: hard at the contact, soft away from it.
* **Ground under a wide light: hard shadows over its disc.** The filter's radius stops at
  MAX_RADIUS_TEXELS, and one radius per point cannot hold both a lamp's dark contact and its wide outer
  penumbra. A light wider than DISC_MIN_DEG (a booth lamp) therefore also draws DISC_DIRECTIONS depth maps,
  one per direction spread over its disc (:func:`station.render.ground.disc_directions`, the directions
  the NumPy ground casts), into one atlas; its ground visibility is the mean of their bilinear 2 × 2
  comparisons, the average of hard shadows over the lamp's disc (a point whose cone towards the lamp
  misses the caster's bounding sphere skips them). Against a brute force of rays over the disc the
  visibility's p95 error went from 0.42 to 0.047 under a 20° lamp (docs/render.md).
* **Model: exponential shadow map.** The model is shaded every frame, where a filtered lookup of several
  taps per light cost the orbit about as much as the rest of the car's shading on llvmpipe. Each
  light's depth map d is therefore filtered once, when drawn, into an ESM_MAP² map of L = (1/c) log of the
  box mean of exp(c d) (in log space, ``shaders/esm.frag.glsl``; c = ESM_SHARPNESS per world unit), of
  half width tan(a) · ESM_REACH; a pixel reads it once, V = min(1, exp(c (L − z))) at its receiver depth z
  (Annen et al. 2008's exponential shadow maps). Behind its blockers by more than a few 1/c (3 cm: 0.25 %
  left) V is the share of the filter's texels that do not block it, i.e. a PCF of fixed width; closer to
  its blocker the shadow is lighter (the exponential's known leak at contacts).
* **What is shadowed.** Only the light's direct part: on the model the light's exact terms on the wide
  lobes and its Lambertian share w_D (N·l)₊Φ/π of the diffuse map (under a clear coat π K_D's share times
  the coat's entry weight ``ClearCoat.entry_scale``(N·l), as the coat map holds it; for the neutral parts,
  their diffuse reflectance's share); the narrow lobes and the flakes' glints, whose maps keep the sun,
  read the maps without the light where it is hidden (``station.render.gl_light_maps``); on the ground
  its direct part (l_y)₊Φ/π. The sky's part of the diffuse and specular maps is not shadowed.
* **Ground ambient occlusion.** Two height maps of the mesh seen from straight above and below
  (HEIGHT_MAP texels on the long side) give, per column (x, z), the mesh's top and bottom heights; the
  mesh is taken as those columns. From a ground point p the cosine-weighted occluded fraction of the sky
  along an azimuth is ∫ 2 sin φ cos φ dφ over the elevations φ the columns hide, sin² φ_max − sin² φ_min
  for the interval [φ_min, φ_max] they span (exact for a convex body, whose slice by a vertical
  half-plane through p is seen from p as one interval of elevations); O is the mean over AO_AZIMUTHS
  azimuths (AO_STEPS columns each), in [0, 1], baked once per mesh into an AO_MAP² map over the ground
  disc's square (``shaders/ao.frag.glsl``). The ground's sky part is then (1 − O) × the sky's irradiance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.render.errors import RenderInputError
from station.render.footprint import bound_points
from station.render.gl_context import build_program
from station.render.ground import AO_AZIMUTHS as AO_AZIMUTHS
from station.render.ground import AO_MAP as AO_MAP
from station.render.ground import AO_STEPS as AO_STEPS
from station.render.ground import CLOSED_SHAPES as CLOSED_SHAPES
from station.render.ground import HEIGHT_MAP as HEIGHT_MAP
from station.render.ground import SHADOW_LIGHTS as SHADOW_LIGHTS
from station.render.ground import SUN_RADIUS_DEG as SUN_RADIUS_DEG
from station.render.ground import disc_directions
from station.render.ground import light_radius_rad as light_radius_rad
from station.render.ground import shadow_lights as shadow_lights
from station.render.shapes import SHAPE_INDEX, SHAPES

#: Texels per side of a light's depth map.
SHADOW_MAP = 2048
#: A receiver is moved this many texels along its normal before its lookup (no self-shadow acne).
NORMAL_OFFSET = 1.5
#: Widest PCF radius, texels (a booth lamp tens of degrees wide is a soft, not a missing, shadow).
MAX_RADIUS_TEXELS = 24.0
#: A light wider than DISC_MIN_DEG (radius, degrees; the sun is 0.27°) bakes the ground from
#: DISC_DIRECTIONS hard shadows instead of the filter above: one depth map of DISC_MAP² texels per direction
#: spread over its disc (``station.render.ground.disc_directions``, as the NumPy ground casts its rays),
#: tiled DISC_COLUMNS across in one atlas per light; a ground point's visibility is the share of the
#: directions whose map does not hide it.
DISC_MIN_DEG = 2.0
DISC_DIRECTIONS = 32
DISC_MAP = 256
DISC_COLUMNS = 8
DISC_ROWS = -(-DISC_DIRECTIONS // DISC_COLUMNS)
#: The model's frames read an exponential shadow map (ESM) of ESM_MAP² texels per light: exp(c d) box-filtered
#: once per light over ESM_TAPS² taps (in log space), one lookup a pixel.
ESM_MAP = 1024
ESM_TAPS = 13
#: Sharpness c of the exponential, per world unit of depth (a receiver 3 cm behind its blocker keeps
#: exp(−6) = 0.25 % of the light).
ESM_SHARPNESS = 200.0
#: Occluder-to-receiver distance (world units) at which the model's penumbra has the light's width:
#: the filter's half width is tan(a) · ESM_REACH (at least 1.5 ESM texels).
ESM_REACH = 0.25


@dataclass(frozen=True)
class OrthoView:
    """An orthographic view: ``matrix`` (4, 4) takes a world point to [0, 1]³ (map u, v and depth, 0 at the
    viewer); ``texel`` the world size of the larger texel side; ``depth`` the world depth over 0 … 1."""

    matrix: NDArray[np.float64]
    texel: float
    depth: float

    def clip(self) -> NDArray[np.float64]:
        """The GL clip matrix of the view: 2 s − 1."""
        to_clip = np.array([[2.0, 0, 0, -1.0], [0, 2.0, 0, -1.0], [0, 0, 2.0, -1.0], [0, 0, 0, 1.0]])
        return to_clip @ self.matrix


def ortho_matrix(
    axes: NDArray, lo: NDArray, hi: NDArray, size: tuple[int, int], margin_texels: float = 4.0
) -> OrthoView:
    """The orthographic view whose rows *axes* (3, 3) are the map's u, v and depth directions (depth
    increasing away from the viewer), fitted to the box [*lo*, *hi*] (world corners) with *margin_texels*
    of border on u and v (*size* = texels on u, v) and 1 % on depth."""
    a = np.asarray(axes, float)
    lo_w, hi_w = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array(
        [[x, y, z] for x in (lo_w[0], hi_w[0]) for y in (lo_w[1], hi_w[1]) for z in (lo_w[2], hi_w[2])]
    )
    proj = corners @ a.T
    p_lo, p_hi = proj.min(axis=0), proj.max(axis=0)
    ext = np.maximum(p_hi - p_lo, 1e-6)
    for k in (0, 1):
        pad = ext[k] * margin_texels / max(size[k] - 2.0 * margin_texels, 1.0)
        p_lo[k] -= pad
        p_hi[k] += pad
    p_lo[2] -= 0.01 * ext[2]
    p_hi[2] += 0.01 * ext[2]
    span = p_hi - p_lo
    m = np.eye(4)
    m[:3, :3] = a / span[:, None]
    m[:3, 3] = -p_lo / span
    return OrthoView(m, float(max(span[0] / size[0], span[1] / size[1])), float(span[2]))


def light_view(direction: NDArray, lo: NDArray, hi: NDArray, size: int = SHADOW_MAP) -> OrthoView:
    """The orthographic view from a light in world *direction* (unit, towards the light) fitted to the box
    [*lo*, *hi*]: depth along −l (0 nearest the light)."""
    ell = np.asarray(direction, float)
    ell = ell / np.linalg.norm(ell)
    f = -ell
    ref = np.array([0.0, 1.0, 0.0]) if abs(f[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    right = np.cross(f, ref)
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    return ortho_matrix(np.array([right, up, f]), lo, hi, (size, size))


def height_views(
    lo: NDArray, hi: NDArray, size: int = HEIGHT_MAP
) -> tuple[OrthoView, OrthoView, tuple[int, int]]:
    """(view from above, view from below, map size) of the box [*lo*, *hi*]: u along +x, v along +z over the
    same rectangle, depth −y from above and +y from below, the long side *size* texels."""
    ext = np.maximum(np.asarray(hi, float) - np.asarray(lo, float), 1e-6)
    nx = size if ext[0] >= ext[2] else max(16, int(math.ceil(size * ext[0] / ext[2])))
    nz = size if ext[2] > ext[0] else max(16, int(math.ceil(size * ext[2] / ext[0])))
    shape = (nx, nz)
    x, y, z = np.eye(3)
    return (
        ortho_matrix(np.array([x, z, -y]), lo, hi, shape),
        ortho_matrix(np.array([x, z, y]), lo, hi, shape),
        shape,
    )


@dataclass(frozen=True)
class ShapeCaster:
    """A ray-cast shape of ``station.render.shapes`` as a shadow caster: *shape* (one of SHAPES) and the
    panels' *misalignment_deg* (degrees; the other shapes ignore it)."""

    shape: str
    misalignment_deg: float = 0.0

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise RenderInputError("shape", " | ".join(SHAPES), self.shape)
        if not math.isfinite(self.misalignment_deg) or abs(self.misalignment_deg) > 45.0:
            raise RenderInputError("misalignment_deg", "-45 <= misalignment_deg <= 45", self.misalignment_deg)

    @property
    def bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(lo, hi): world corners of a box holding the shape (the footprint's bound points)."""
        pts = bound_points(self.shape, self.misalignment_deg)
        return pts.min(axis=0), pts.max(axis=0)

    @property
    def closed(self) -> bool:
        """Whether the shape is a closed solid, so its height maps give the ground's ambient occlusion."""
        return self.shape in CLOSED_SHAPES


def _cols(m: NDArray) -> tuple[float, ...]:
    return tuple(float(v) for v in np.asarray(m, float).T.ravel())  # column-major for GL


class ShadowMaps:
    """The depth maps of the shadowed lights and the ground's ambient-occlusion map of one mesh on a GL
    context (module docstring); redrawn only when :meth:`update`'s key changes. ``version`` counts the
    redraws (the ground bake keys on it)."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self.version = 0
        self._depth_prog = build_program(ctx, "shadow_depth.vert.glsl", "shadow_depth.frag.glsl")
        self._cast: dict[str, tuple[Any, Any]] = {}  # shape → (ray-cast depth program, vertex array)
        self._ao_prog = build_program(ctx, "fullscreen.vert.glsl", "ao.frag.glsl", _ao_defines())
        self._ao_vao = ctx.vertex_array(self._ao_prog, [])
        self._esm_prog = build_program(ctx, "fullscreen.vert.glsl", "esm.frag.glsl", {"ESM_TAPS": ESM_TAPS})
        self._esm_vao = ctx.vertex_array(self._esm_prog, [])
        # (texture, framebuffer): [0] the filter's scratch, then one per light
        self._esm: list[tuple[Any, Any]] = []
        self._esm_c: list[float] = []
        self._maps: list[
            tuple[Any, Any, Any, Any]
        ] = []  # (texture, framebuffer, compare sampler, raw sampler)
        self._views: list[OrthoView] = []
        self._radii: list[float] = []
        # per light slot: (atlas texture, framebuffer, compare sampler) of its disc's depth maps, made once
        self._disc: list[tuple[Any, Any, Any]] = []
        # per light slot: its disc's views ([] for a narrow light)
        self._disc_views: list[list[OrthoView]] = []
        # the caster's bounding sphere (world centre, radius)
        self._bound: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)
        self._key: tuple | None = None
        self._held: Any = None  # the mesh of the key (so its id is not reused while cached)
        self._mesh_buf: tuple | None = None  # (mesh, vbo, ibo, vao)
        self._heights: list[tuple[Any, Any]] = []
        self._ao: tuple[Any, Any] | None = None
        self._ao_key: tuple | None = None
        self._ao_caster: Any = None

    def _vao(self, mesh: Any) -> Any:
        if self._mesh_buf is None or self._mesh_buf[0] is not mesh:
            self._release_mesh()
            vbo = self.ctx.buffer(np.ascontiguousarray(mesh.positions, np.float32).tobytes())
            ibo = self.ctx.buffer(np.ascontiguousarray(mesh.faces, np.uint32).tobytes())
            vao = self.ctx.vertex_array(
                self._depth_prog, [(vbo, "3f", "in_pos")], index_buffer=ibo, index_element_size=4
            )
            self._mesh_buf = (mesh, vbo, ibo, vao)
        return self._mesh_buf[3]

    def _depth_target(self, size: tuple[int, int]) -> tuple[Any, Any]:
        tex = self.ctx.depth_texture(size)
        tex.repeat_x = tex.repeat_y = False
        tex.compare_func = ""
        tex.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        return tex, self.ctx.framebuffer(depth_attachment=tex)

    def _esm_target(self) -> tuple[Any, Any]:
        tex = self.ctx.texture((ESM_MAP, ESM_MAP), 1, dtype="f4")
        tex.repeat_x = tex.repeat_y = False
        return tex, self.ctx.framebuffer(color_attachments=[tex])

    def _light_target(self) -> tuple[Any, Any, Any, Any]:
        tex, fbo = self._depth_target((SHADOW_MAP, SHADOW_MAP))
        cmp = self.ctx.sampler(texture=tex, repeat_x=False, repeat_y=False, compare_func="<=")
        raw = self.ctx.sampler(
            texture=tex,
            repeat_x=False,
            repeat_y=False,
            filter=(self.ctx.NEAREST, self.ctx.NEAREST),
            compare_func="",
        )
        return tex, fbo, cmp, raw

    def _cast_vao(self, caster: ShapeCaster) -> Any:
        if caster.shape not in self._cast:
            prog = build_program(
                self.ctx,
                "fullscreen.vert.glsl",
                "shadow_cast.frag.glsl",
                {"SHAPE": SHAPE_INDEX[caster.shape]},
            )
            self._cast[caster.shape] = (prog, self.ctx.vertex_array(prog, []))
        prog, vao = self._cast[caster.shape]
        if "u_misalign" in prog:
            prog["u_misalign"].value = math.radians(caster.misalignment_deg)
        return vao

    def _draw_depth(
        self,
        fbo: Any,
        view: OrthoView,
        vao: Any,
        size: tuple[int, int] | None = None,
        from_below: bool = False,
        origin: tuple[int, int] | None = None,
    ) -> None:
        """Depth of the caster whose vertex array is *vao* in *view* into *fbo* (*size*: its texels): a
        mesh rasterised, or a ray-cast shape's full-screen pass (``shaders/shadow_cast.frag.glsl``;
        *from_below*: the height map from below). *origin*: into the tile of *size* texels at that texel
        of *fbo* (an atlas, cleared beforehand), else into the whole of *fbo*, cleared first."""
        if origin is None:
            fbo.viewport = (0, 0, *fbo.size)
            fbo.use()
            fbo.clear(depth=1.0)
        else:
            fbo.viewport = (*origin, *(size or fbo.size))
            fbo.use()
        cast = next((p for p, v in self._cast.values() if v is vao), None)
        if cast is None:
            self._depth_prog["u_clip"].value = _cols(view.clip())
        else:
            inv = np.linalg.inv(view.matrix)
            axis = view.matrix[2, :3]
            cast["u_inv"].value = _cols(inv)
            cast["u_dir"].value = tuple(float(v) for v in axis / np.linalg.norm(axis))
            cast["u_depth"].value = float(view.depth)
            cast["u_size"].value = tuple(float(v) for v in (size or fbo.size))
            if "u_origin" in cast:
                cast["u_origin"].value = tuple(float(v) for v in (origin or (0, 0)))
            if "u_from_below" in cast:  # the cylinder's only
                cast["u_from_below"].value = int(from_below)
        self.ctx.enable(self.ctx.DEPTH_TEST)
        try:
            if cast is None:
                vao.render(mode=self.ctx.TRIANGLES)
            else:
                vao.render(mode=self.ctx.TRIANGLES, vertices=3)
        finally:
            self.ctx.disable(self.ctx.DEPTH_TEST)

    def _caster_vao(self, caster: Any) -> Any:
        """The vertex array that draws *caster*'s depth: a mesh's triangles or a shape's ray cast."""
        return self._cast_vao(caster) if isinstance(caster, ShapeCaster) else self._vao(caster)

    @staticmethod
    def _ident(caster: Any) -> object:
        """What identifies *caster* in a cache key: the shape caster itself (a value), a mesh by id."""
        return caster if isinstance(caster, ShapeCaster) else id(caster)

    def _holds(self, caster: Any) -> bool:
        return self._held == caster if isinstance(caster, ShapeCaster) else self._held is caster

    def update(self, mesh: Any, lights: Any, slots: tuple[int, ...], rotation: NDArray) -> None:
        """Draw the depth maps of the lights *slots* of *lights* (map-frame directions; world = Rᵀ l with
        *rotation* R the environment's lookup matrix) for *mesh* (a mesh or a :class:`ShapeCaster`), unless
        they are already those."""
        key = (
            self._ident(mesh),
            tuple(slots),
            np.asarray(rotation, float).tobytes(),
            np.asarray(lights.directions).tobytes(),
        )
        if key == self._key and self._holds(mesh):
            return
        lo, hi = mesh.bounds
        centre = 0.5 * (np.asarray(lo, float) + np.asarray(hi, float))
        half = 0.5 * float(np.linalg.norm(np.asarray(hi, float) - np.asarray(lo, float)))
        self._bound = (*(float(v) for v in centre), half)
        vao = self._caster_vao(mesh)
        while len(self._maps) < len(slots):
            self._maps.append(self._light_target())
        while len(self._esm) < len(slots) + 1:
            self._esm.append(self._esm_target())
        self._esm_c = []
        self._views, self._radii, self._disc_views = [], [], []
        spreads = lights.spreads()
        for k, i in enumerate(slots):
            world = np.asarray(rotation, float).T @ np.asarray(lights.directions[i], float)
            view = light_view(world, lo, hi)
            self._draw_depth(self._maps[k][1], view, vao, (SHADOW_MAP, SHADOW_MAP))
            self._views.append(view)
            self._radii.append(light_radius_rad(float(spreads[i])))
            self._filter_esm(k, view, self._radii[-1])
            self._disc_views.append(self._draw_disc(k, world, self._radii[-1], lo, hi, vao))
        self._key, self._held = key, mesh
        self.version += 1

    def _disc_target(self, k: int) -> tuple[Any, Any, Any]:
        while len(self._disc) <= k:
            tex, fbo = self._depth_target((DISC_COLUMNS * DISC_MAP, DISC_ROWS * DISC_MAP))
            cmp = self.ctx.sampler(texture=tex, repeat_x=False, repeat_y=False, compare_func="<=")
            self._disc.append((tex, fbo, cmp))
        return self._disc[k]

    def _draw_disc(
        self, k: int, world: NDArray, radius_rad: float, lo: NDArray, hi: NDArray, vao: Any
    ) -> list[OrthoView]:
        """Light slot *k*'s disc atlas (module docstring): the depth maps of DISC_DIRECTIONS directions
        over the disc of angular radius *radius_rad* about its world direction *world*, each fitted to the
        box [*lo*, *hi*]; their views in tile order. None drawn (``[]``) for a light of DISC_MIN_DEG or less."""
        if radius_rad <= math.radians(DISC_MIN_DEG):
            return []
        _, fbo, _ = self._disc_target(k)
        fbo.viewport = (0, 0, *fbo.size)
        fbo.use()
        fbo.clear(depth=1.0)
        views = []
        for j, direction in enumerate(disc_directions(world, radius_rad, DISC_DIRECTIONS)):
            view = light_view(direction, lo, hi, DISC_MAP)
            origin = ((j % DISC_COLUMNS) * DISC_MAP, (j // DISC_COLUMNS) * DISC_MAP)
            self._draw_depth(fbo, view, vao, (DISC_MAP, DISC_MAP), origin=origin)
            views.append(view)
        fbo.viewport = (0, 0, *fbo.size)
        return views

    def _filter_esm(self, k: int, view: OrthoView, radius_rad: float) -> None:
        """Light slot *k*'s exponential shadow map: its depth map box-filtered in log space, across then
        down, over a half width tan(a) · ESM_REACH (``shaders/esm.frag.glsl``)."""
        texel = view.texel * SHADOW_MAP / ESM_MAP
        half = max(math.tan(radius_rad) * ESM_REACH, 1.5 * texel) / texel  # ESM texels
        step = 2.0 * half / (ESM_TAPS - 1) / ESM_MAP
        c = ESM_SHARPNESS * view.depth  # per unit of the map's depth
        p = self._esm_prog
        p["u_c"].value = c
        p["u_size"].value = (float(ESM_MAP), float(ESM_MAP))
        p["u_src"].value = 0
        passes = (
            (self._maps[k][0], self._esm[0], (step, 0.0)),
            (self._esm[0][0], self._esm[k + 1], (0.0, step)),
        )
        for src, dst, direction in passes:
            src.use(0)
            p["u_step"].value = direction
            dst[1].use()
            self._esm_vao.render(mode=self.ctx.TRIANGLES, vertices=3)
        self._esm_c.append(c)

    def ambient_occlusion(
        self, mesh: Any, ground_y: float, centre: tuple[float, float], radius: float
    ) -> Any:
        """The AO_MAP² occlusion map (R: O in [0, 1]) of *mesh* (a mesh or a closed :class:`ShapeCaster`)
        over the ground disc's square (centre (x, z), *radius*) at height *ground_y*, baked once per caster
        and ground (module docstring)."""
        if isinstance(mesh, ShapeCaster) and not mesh.closed:
            raise RenderInputError("shape", " | ".join(CLOSED_SHAPES), mesh.shape)
        key = (self._ident(mesh), float(ground_y), tuple(float(c) for c in centre), float(radius))
        if self._ao is not None and self._ao_key == key and self._ao_held(mesh):
            return self._ao[0]
        lo, hi = mesh.bounds
        top, bottom, shape = height_views(lo, hi)
        if not self._heights or self._heights[0][0].size != shape:
            for tex, fbo in self._heights:
                fbo.release()
                tex.release()
            self._heights = [self._depth_target(shape) for _ in (0, 1)]
        vao = self._caster_vao(mesh)
        for (_, fbo), view, below in zip(self._heights, (top, bottom), (False, True), strict=True):
            self._draw_depth(fbo, view, vao, shape, below)
        if self._ao is None:
            tex = self.ctx.texture((AO_MAP, AO_MAP), 1, dtype="f4")
            tex.repeat_x = tex.repeat_y = False
            self._ao = (tex, self.ctx.framebuffer(color_attachments=[tex]))
        self._ao[1].use()
        for unit, (tex, _) in enumerate(self._heights):
            tex.use(unit)
        p = self._ao_prog
        p["u_top"].value, p["u_bottom"].value = 0, 1
        p["u_box_lo"].value = (float(lo[0]), float(lo[2]))
        p["u_box_hi"].value = (float(hi[0]), float(hi[2]))
        p["u_top_mat"].value = _cols(top.matrix)
        # depth d of a view maps back to the height y = −(lo + d span) from above, lo + d span from below
        p["u_heights"].value = (
            float(-top.matrix[2, 3] * top.depth),
            top.depth,
            float(-bottom.matrix[2, 3] * bottom.depth),
            bottom.depth,
        )
        p["u_ground_y"].value = float(ground_y)
        p["u_ground_c"].value = (float(centre[0]), float(centre[1]))
        p["u_ground_radius"].value = float(radius)
        p["u_size"].value = (float(AO_MAP), float(AO_MAP))
        self._ao_vao.render(mode=self.ctx.TRIANGLES, vertices=3)
        self._ao_key, self._ao_caster = key, mesh
        self.version += 1
        return self._ao[0]

    def _ao_held(self, caster: Any) -> bool:
        if isinstance(caster, ShapeCaster):
            return bool(self._ao_caster == caster)
        return self._mesh_buf is not None and self._mesh_buf[0] is caster and self._ao_caster is caster

    def bind(self, first_unit: int, count: int, disc_unit: int) -> dict[str, Any]:
        """Bind the first *count* light maps (compare and raw samplers) from texture unit *first_unit* on, their
        disc atlases from *disc_unit* on (a narrow light's compare sampler in its place), and return their
        uniforms (the ``_shadow_*`` arrays go through ``set_uniforms``)."""
        identity = np.eye(4).ravel()
        disc_mat: list[NDArray] = []
        for k in range(count):
            self._maps[k][2].use(first_unit + k)
            self._maps[k][3].use(first_unit + count + k)
            self._esm[k + 1][0].use(first_unit + 2 * count + k)
            views = self._disc_views[k]
            (self._disc[k][2] if views else self._maps[k][2]).use(disc_unit + k)
            disc_mat += [v.matrix.T.ravel() for v in views] or [identity] * DISC_DIRECTIONS
        return {
            "_shadow_disc": list(range(disc_unit, disc_unit + count)),
            "_shadow_disc_mat": disc_mat,
            "_shadow_disc_par": [
                (v[0].texel, v[0].depth, math.tan(self._radii[k])) if v else (1.0, 1.0, 0.0)
                for k, v in enumerate(self._disc_views[:count])
            ],
            "u_shadow_bound": self._bound,
            "_shadow_esm": list(range(first_unit + 2 * count, first_unit + 3 * count)),
            "_shadow_c": list(self._esm_c[:count]),
            "_shadow_cmp": list(range(first_unit, first_unit + count)),
            "_shadow_raw": list(range(first_unit + count, first_unit + 2 * count)),
            "_shadow_mat": [self._views[k].matrix.T.ravel() for k in range(count)],
            "_shadow_par": [
                (self._views[k].texel, self._views[k].depth, math.tan(self._radii[k])) for k in range(count)
            ],
        }

    def _release_mesh(self) -> None:
        if self._mesh_buf is not None:
            for obj in reversed(self._mesh_buf[1:]):
                obj.release()
            self._mesh_buf = None

    def release(self) -> None:
        """Free the maps, samplers, buffers and programs."""
        self._release_mesh()
        for tex, fbo, cmp, raw in self._maps:
            for obj in (cmp, raw, fbo, tex):
                obj.release()
        for tex, fbo, cmp in self._disc:
            for obj in (cmp, fbo, tex):
                obj.release()
        self._disc, self._disc_views = [], []
        for tex, fbo in self._heights:
            fbo.release()
            tex.release()
        if self._ao is not None:
            self._ao[1].release()
            self._ao[0].release()
        for tex, fbo in self._esm:
            fbo.release()
            tex.release()
        for prog, vao in self._cast.values():
            vao.release()
            prog.release()
        self._cast = {}
        self._esm_vao.release()
        self._esm_prog.release()
        self._esm = []
        self._ao_vao.release()
        self._ao_prog.release()
        self._depth_prog.release()
        self._maps, self._heights, self._ao = [], [], None
        self._key = self._held = self._ao_key = self._ao_caster = None


def _ao_defines() -> dict[str, object]:
    return {"AO_AZIMUTHS": AO_AZIMUTHS, "AO_STEPS": AO_STEPS}


def shadow_defines(slots: tuple[int, ...], ambient: bool) -> dict[str, object]:
    """The defines of ``shaders/shadows.glsl`` for a frame: N_SHADOW maps, the light index of each
    (SHADOW_L0, SHADOW_L1; −1 when unused), HAS_AO, and the lookup's constants."""
    padded = (*slots, -1, -1)
    return {
        "N_SHADOW": len(slots),
        "SHADOW_L0": padded[0],
        "SHADOW_L1": padded[1],
        "HAS_AO": int(ambient),
        "SHADOW_NORMAL_OFFSET": f"{NORMAL_OFFSET:.3f}",
        "SHADOW_MAX_RADIUS": f"{MAX_RADIUS_TEXELS:.3f}",
        "DISC_DIRECTIONS": DISC_DIRECTIONS,
        "DISC_COLUMNS": DISC_COLUMNS,
        "DISC_ROWS": DISC_ROWS,
    }
