"""A mesh's depth pre-pass (``GLRenderer.mesh_prepass``, ``FramePasses._draw_mesh``): the mesh's depth first,
then the stage and the mesh's programs (the paint's triangles with the paint's, the neutral parts' with
theirs) each where they are seen, so every pixel is shaded once, by its own material's code. The frame must
be the one the plain depth-tested draw of one program gives, bit for bit, whatever the triangles' order
(where two triangles lie at the same depth the last drawn shows instead of the first: none do here)."""

from __future__ import annotations

import numpy as np
import pytest

from station.model.flakes import METALLIC_FLAKES
from station.model.gloss import ClearCoat
from station.render import meshes as me
from station.render import prefilter, procedural
from station.render.camera import Camera
from station.render.car import car_body
from station.render.gl_renderer import GLRenderer
from station.render.numpy_renderer import BACKGROUND
from station.render.stage import Stage
from tests.render.test_meshes import EXPS, _pair

#: Looking at the boxes' near faces from the front and a little above, the far box's top showing.
FRONT = Camera((0.0, 1.2, 4.0), (0.0, 0.0, 0.0), fov_deg=35.0)
#: The procedural car from its front quarter, close enough that its wheels, glass and body overlap.
CAR = Camera((3.2, 1.4, 3.6), (0.0, 0.45, 0.0), fov_deg=32.0)
SIZE = 96


def _far_first_boxes() -> me.Mesh:
    """Two boxes, the far one's triangles first, painted, and the near one wholly in front of it, glass: the
    plain draw shades the far box where the near one then covers it."""
    import trimesh

    far = trimesh.creation.box((1.6, 1.0, 0.6))
    far.apply_translation((0.2, 0.0, -0.5))
    near = trimesh.creation.box((1.0, 0.7, 0.6))
    near.apply_translation((-0.2, -0.1, 0.35))
    v = np.concatenate([far.vertices, near.vertices]).astype(np.float32)
    faces = np.concatenate([far.faces, near.faces + len(far.vertices)]).astype(np.uint32)
    normals = np.concatenate([far.vertex_normals, near.vertex_normals]).astype(np.float32)
    painted = np.concatenate([np.full(len(far.vertices), me.PAINT), np.full(len(near.vertices), me.GLASS)])
    return me.Mesh("far-first", v, normals, faces, painted.astype(np.float32))


@pytest.fixture(scope="module")
def sky_basis():
    return prefilter.prefilter_basis(procedural.sunny_sky(128), EXPS, max_size=32)


def _frames(gl: GLRenderer, mesh: me.Mesh, camera: Camera, **kw) -> tuple[np.ndarray, np.ndarray]:
    """The 8-bit and the linear frame of *mesh* (render_mesh's keywords *kw*)."""
    display = gl.render_mesh(mesh, _pair(), camera=camera, **kw).copy()
    linear = gl.render_mesh(mesh, _pair(), camera=camera, linear=True, **kw).copy()
    return display, linear


def _one_material(mesh: me.Mesh, code: float) -> me.Mesh:
    return me.Mesh(mesh.name, mesh.positions, mesh.normals, mesh.faces, np.full_like(mesh.painted, code))


@pytest.mark.gl
@pytest.mark.parametrize("aa", [1, 4])
@pytest.mark.parametrize("which", ["boxes", "car", "paint alone", "parts alone"])
def test_prepass_draws_the_frame_the_plain_draw_does(gl_ctx, sky_basis, which: str, aa: int) -> None:
    """The pre-pass and the two programs by material (the paint's triangles, then the neutral parts') draw
    the frame of one program drawing the triangles as they come: with both materials, either alone."""
    mesh, camera = (car_body(), CAR) if which == "car" else (_far_first_boxes(), FRONT)
    if which != "car" and which != "boxes":
        mesh = _one_material(mesh, me.PAINT if which == "paint alone" else me.TYRE)
    scenes = [
        {},
        {"stage": Stage(), "coat": ClearCoat(), "flakes": METALLIC_FLAKES, "exposure_ev": 0.5},
    ]
    with GLRenderer(sky_basis, SIZE, SIZE, ctx=gl_ctx, aa=aa) as gl:
        assert gl.mesh_prepass  # the default
        for kw in scenes:
            with_pre = _frames(gl, mesh, camera, **kw)
            gl.mesh_prepass = False
            plain = _frames(gl, mesh, camera, **kw)
            gl.mesh_prepass = True
            for a, b in zip(with_pre, plain, strict=True):
                assert np.array_equal(a, b)
            if not kw:  # the mesh fills a good part of the frame: the comparison is not of the background
                assert (np.abs(with_pre[1] - BACKGROUND).max(axis=-1) > 1e-6).mean() > 0.1


@pytest.mark.gl
def test_the_near_box_is_seen_where_it_lies(gl_ctx, sky_basis) -> None:
    """Where the near box (glass, drawn last) lies, the frame is the near box's alone, and elsewhere the far
    box's alone: the depth kept is the nearest, not the last drawn, and the stage is seen around both."""
    mesh = _far_first_boxes()
    parts = {
        "far": me.Mesh("far", mesh.positions, mesh.normals, mesh.faces[:12], mesh.painted),
        "near": me.Mesh("near", mesh.positions, mesh.normals, mesh.faces[12:], mesh.painted),
    }
    with GLRenderer(sky_basis, SIZE, SIZE, ctx=gl_ctx) as gl:
        both = gl.render_mesh(mesh, _pair(), camera=FRONT, linear=True)
        alone = {k: gl.render_mesh(m, _pair(), camera=FRONT, linear=True) for k, m in parts.items()}
    near = np.abs(alone["near"] - BACKGROUND).max(axis=-1) > 1e-6
    far = np.abs(alone["far"] - BACKGROUND).max(axis=-1) > 1e-6
    assert near.sum() > 500 and (far & ~near).sum() > 200 and (far & near).sum() > 200  # they overlap
    assert np.array_equal(both[near], alone["near"][near])
    assert np.array_equal(both[far & ~near], alone["far"][far & ~near])
    assert np.all(both[~far & ~near] == np.float32(BACKGROUND))
