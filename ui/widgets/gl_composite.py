"""The GL composite of the cached basis images (gpu mode of :class:`ui.widgets.gl_render_view.GLRenderView`):
``shaders/composite.*.glsl`` compiled for a layer count, and its uniforms written from both paints' lobe
weights and the display settings."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from station.render.numpy_renderer import BACKGROUND
from ui.models.view import BasisImages, layer_weights

SHADER_DIR = Path(__file__).resolve().parents[1] / "shaders"

if TYPE_CHECKING:
    import moderngl

    from station.render.weights import LobeWeights


def composite_program(ctx: moderngl.Context, layers: int) -> moderngl.Program:
    """Compile ``shaders/composite.*.glsl`` for a basis of *layers* cached images."""
    frag = (
        (SHADER_DIR / "composite.frag.glsl")
        .read_text()
        .replace("#version 330", f"#version 330\n#define MAX_LAYERS {layers}", 1)
    )
    return ctx.program(vertex_shader=(SHADER_DIR / "composite.vert.glsl").read_text(), fragment_shader=frag)


def uniform(prog: moderngl.Program, name: str) -> moderngl.Uniform:
    """The uniform *name* of *prog* (a program member of another kind is a shader error)."""
    import moderngl

    member = prog[name]
    if not isinstance(member, moderngl.Uniform):
        raise TypeError(f"{name}: expected a uniform of the program, got {type(member).__name__}")
    return member


def set_composite_uniforms(
    prog: moderngl.Program,
    basis: BasisImages,
    weights: tuple[LobeWeights, LobeWeights],
    exposure_ev: float,
    viewport: tuple[int, int],
) -> None:
    """Write both paints' per-image weights (:func:`ui.models.view.layer_weights`) and display settings."""
    (a0, b0), (a1, b1) = (layer_weights(basis.layout, w) for w in weights)
    k = len(basis.layout)
    active = [j for j in range(k) if a0[j].any() or b0[j].any() or a1[j].any() or b1[j].any()]
    pad = np.zeros((k - len(active), 3))
    uniform(prog, "u_n_active").value = len(active)
    uniform(prog, "u_layer").write(np.array(active + [0] * (k - len(active)), "i4").tobytes())
    for name, arr in (("u_a0", a0), ("u_b0", b0), ("u_a1", a1), ("u_b1", b1)):
        uniform(prog, name).write(np.concatenate([arr[active], pad]).astype("f4").tobytes())
    uniform(prog, "u_exposure").value = float(2.0**exposure_ev)
    uniform(prog, "u_background").value = (BACKGROUND,) * 3
    uniform(prog, "u_viewport").value = tuple(map(float, viewport))
    uniform(prog, "u_size").value = basis.size
