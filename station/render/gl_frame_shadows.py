"""The shadow state of one GL renderer (:class:`FrameShadows`): which extracted lights cast shadow maps,
the maps and the ground's ambient-occlusion map of the frame's caster (a mesh or the scene's ray-cast
shape), drawn when the caster, the environment's turn or the ground change and bound for a frame. The
maps themselves, their filtering and lookups: :mod:`station.render.gl_shadows`."""

from __future__ import annotations

from typing import Any

import numpy as np

from station.render import gl_textures as tx
from station.render.errors import RenderError, RenderInputError
from station.render.gl_light_maps import ShadowedMaps
from station.render.gl_shadows import SHADOW_LIGHTS, ShadowMaps, ShapeCaster, shadow_lights
from station.render.numpy_renderer import check_paints
from station.render.shapes import CONVEX_SHAPES, GROUNDS, Scene
from station.render.stage import lookup_matrix

__all__ = ["COARSE_UNIT", "SHADOWED_UNIT", "SHADOW_UNIT", "FrameShadows", "probe_shadows"]

#: First texture unit of the shadow maps past the lobe count m (units m .. m + 10 hold the frame's own maps).
SHADOW_UNIT = 11
#: First texture unit of the maps without the shadowed lights past m: after the shadow maps (three a light)
#: and the ground's occlusion map.
SHADOWED_UNIT = SHADOW_UNIT + 3 * SHADOW_LIGHTS + 1
#: Texture unit (after the lobes) of the first light's disc atlas (the ground's bake; gl_shadows.DISC_MIN_DEG),
#: after the maps without the shadowed lights (four a light, station.render.gl_light_maps).
DISC_UNIT = SHADOWED_UNIT + 4 * SHADOW_LIGHTS
#: Texture units (after the lobes) of the coarse pass's two maps (station.render.gl_passes.COARSE_FACTOR),
#: after the disc atlases.
COARSE_UNIT = DISC_UNIT + SHADOW_LIGHTS


class FrameShadows:
    """Shadow maps of the strongest lights taken out of the environment (*lights*:
    ``PrefilteredBasis.lights`` in binding order, or None) for the frames of one renderer on *ctx*."""

    def __init__(self, ctx: Any, lights: Any, shadowed: ShadowedMaps | None = None) -> None:
        self.ctx = ctx
        self.lights = lights
        #: Indices of the lights that cast shadow maps (:func:`station.render.gl_shadows.shadow_lights`).
        self.slots = shadow_lights(lights)
        self.maps: ShadowMaps | None = None
        #: The maps without each shadowed light (narrow lobes, glints: gl_light_maps), made on first use.
        self.shadowed = shadowed

    @staticmethod
    def caster(scene: Any, mesh: Any) -> Any:
        """What casts the frame's shadows: *mesh*, else the scene's ray-cast shape (a ShapeCaster)."""
        return mesh if mesh is not None else ShapeCaster(scene.shape, scene.misalignment_deg)

    @staticmethod
    def floor(scene: Any, mesh: Any) -> tuple[float, tuple[float, float]]:
        """(ground height y, ground centre (x, z)) under *mesh* or the scene's shape (shapes.GROUNDS)."""
        if mesh is not None:
            return float(mesh.floor_y), (0.0, 0.0)
        gx, gy, gz = GROUNDS[scene.shape]
        return float(gy), (float(gx), float(gz))

    def key(self, scene: Any, mesh: Any, on: bool, probe: bool = False) -> tuple:
        """(shadowed light indices, ambient occlusion on, probe) of a frame: a mesh or a ray-cast shape on a
        stage with shadows *on* and lights taken out of the environment; () otherwise. The ambient
        occlusion needs a ground and a closed caster (a mesh, or ShapeCaster.closed)."""
        if scene.stage is None or not on or not self.slots:
            return ()
        closed = mesh is not None or self.caster(scene, mesh).closed
        return (self.slots, bool(scene.stage.ground) and closed, bool(probe))

    def object_key(self, scene: Any, mesh: Any, shadows: bool, object_shadows: bool, probe: bool) -> tuple:
        """:meth:`key` of the object's own shading, the renderer's *shadows* and *object_shadows* switches
        given: () where the object is not shadowed (the ground's bake keeps its maps), and for a ray-cast
        shape of CONVEX_SHAPES, which cannot shadow itself (the same frame, shaded cheaper), unless *probe*."""
        own = object_shadows and (mesh is not None or scene.shape not in CONVEX_SHAPES)
        return self.key(scene, mesh, shadows and (own or probe), probe)

    @property
    def version(self) -> int:
        """How many times the shadow or ambient-occlusion maps were drawn (-1 before the first)."""
        return -1 if self.maps is None else self.maps.version

    def update(self, scene: Any, mesh: Any, objects: tuple = (), mw: Any = None, flakes: Any = None) -> None:
        """Draw the shadow maps and the ground's occlusion map of *mesh* (or the scene's shape) when they
        changed and, with *objects* (:meth:`object_key`: the object is shadowed), the maps without each
        shadowed light for the paints' bound weights *mw* and the glints of *flakes*
        (:meth:`station.render.gl_light_maps.ShadowedMaps.prepare`). They draw on their own targets: called
        before the frame binds its framebuffer and textures."""
        if self.maps is None:
            self.maps = ShadowMaps(self.ctx)
        caster = self.caster(scene, mesh)
        self.maps.update(caster, self.lights, self.slots, lookup_matrix(scene.stage.rotation_deg))
        if self.key(scene, mesh, True)[1]:
            floor_y, centre = self.floor(scene, mesh)
            self.maps.ambient_occlusion(caster, floor_y, centre, scene.stage.ground_radius)
        if objects and self.shadowed is not None:
            self.shadowed.prepare(self.slots, mw, flakes)

    def bind(
        self, scene: Any, mesh: Any, m: int, objects: tuple = (), mw: Any = None, flakes: Any = None
    ) -> dict:
        """Bind the shadow maps (texture units m + SHADOW_UNIT on) and the ground's occlusion map; their uniforms.
        With *objects* (the frame's :meth:`object_key`: the object is shadowed) also the maps without each
        shadowed light, the narrow lobes' for the paints' bound weights *mw* and the glints of *flakes* (units
        m + SHADOWED_UNIT on, :meth:`station.render.gl_light_maps.ShadowedMaps.bind`; drawn by :meth:`update`)."""
        maps = self.maps
        if maps is None:
            raise RenderError("shadow maps bound before they were drawn")
        n = len(self.slots)
        uniforms = maps.bind(m + SHADOW_UNIT, n, m + DISC_UNIT)
        if self.key(scene, mesh, True)[1]:
            floor_y, centre = self.floor(scene, mesh)
            ao = maps.ambient_occlusion(self.caster(scene, mesh), floor_y, centre, scene.stage.ground_radius)
            ao.use(m + SHADOW_UNIT + 3 * n)
            uniforms["u_ao"] = m + SHADOW_UNIT + 3 * n
        if objects and self.shadowed is not None:
            uniforms.update(self.shadowed.bind(self.slots, mw, flakes, m + SHADOWED_UNIT))
        return uniforms

    def release(self) -> None:
        """Free the maps."""
        if self.shadowed is not None:
            self.shadowed.release()
        if self.maps is not None:
            self.maps.release()
            self.maps = None


def probe_shadows(
    renderer: Any,
    mesh: Any,
    paints: Any,
    camera: Any = None,
    stage: Any = None,
    size: int = 512,
    shape: str = "sphere",
    misalignment_deg: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Diagnostics (``GLRenderer.shadow_probe``; *renderer* a ``station.render.gl_renderer.GLRenderer``,
    imported by that module, so not imported here) of the shadows of *mesh*, or with *mesh* None of the ray-cast *shape* (of
    ``station.render.shapes``; *misalignment_deg* the panels'), :mod:`station.render.gl_shadows`, by the
    frame's own shader functions: (ground (size, size, 3) float32 over the ground disc's square, row 0
    at z = centre − radius, column 0 at x = centre − radius: visibility of the strongest and the second
    light, 1 − O; model (H, W, 4) float32 from *camera* (default MESH_CAMERA, or the shape's): the
    strongest light's visibility on the model and the world point x, y, z; visibility −1 where the
    model is not; at ``aa`` 1, as a supersampled frame averages neighbouring pixels' values). Lights
    without a map read 1 (and 1 − O reads 1 without an occlusion map: an open shape); RenderInputError
    naming ``mesh`` when the frame has no shadow maps (no lights, no stage, or :attr:`shadows` off)."""
    from station.render.meshes import MESH_CAMERA
    from station.render.stage import Stage

    if mesh is None:
        scene = Scene(shape, misalignment_deg, camera=camera, stage=stage or Stage())
    else:
        scene = Scene("sphere", camera=camera or MESH_CAMERA, stage=stage or Stage())
    if not renderer._frame_shadows.key(scene, mesh, renderer.shadows):
        name = shape if mesh is None else mesh.name
        raise RenderInputError("mesh", "a model on a stage lit by extracted lights, shadows on", name)
    fbo = renderer._draw(scene, paints, True, 0.0, "clip", None, mesh=mesh, probe=True)
    data = np.frombuffer(fbo.read(components=4, dtype="f4", alignment=1), np.float32)
    model = data.reshape(renderer.height, renderer.width, 4)[::-1].copy()
    tex = tx.colour_texture(renderer.ctx, (size, size), False)
    target = renderer.ctx.framebuffer(color_attachments=[tex])
    try:
        shadow = (*renderer._frame_shadows.key(scene, mesh, renderer.shadows)[:2], True)
        prog, vao = renderer._passes.program("sphere", True, "ground", (0, 1, 0), shadow=shadow)
        pair = check_paints(renderer.basis, paints)
        uniforms, mw, m = renderer._frame_uniforms(scene, pair, target, None, mesh, None, {})
        uniforms.update(renderer._frame_shadows.bind(scene, mesh, m))
        renderer._set_uniforms(
            prog, {**uniforms, "u_size": (float(size),) * 2}, mw, np.zeros((8, 4), np.float32), m
        )
        target.use()
        vao.render(mode=renderer.ctx.TRIANGLES, vertices=3)
        ground = np.frombuffer(target.read(components=3, dtype="f4", alignment=1), np.float32)
    finally:
        target.release()
        tex.release()
    return ground.reshape(size, size, 3).copy(), model
