"""The one OpenGL context factory of the renderer and the shader loader every GL pass shares.

A context is a standalone headless EGL context at OpenGL ≥ 4.3 (Mesa llvmpipe on CPU-only machines,
the GPU driver where one exists) with seamless cube-map filtering enabled; when none can be made,
:class:`~station.render.errors.GLUnavailableError` says why. Shaders live in ``shaders/*.glsl``; a line
``//#include NAME.glsl`` is replaced by that file, and ``#define`` lines may be injected after the
``#version`` line.

This module sits below every GL user (``prefilter``, ``gl_renderer``) and imports none of them, so
the renderer's modules import in one direction only: ``gl_renderer → numpy_renderer → prefilter →
gl_context``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from station.render.errors import GLUnavailableError, RenderError

SHADER_DIR = Path(__file__).resolve().parent / "shaders"
GL_TEXTURE_CUBE_MAP_SEAMLESS = 0x884F
#: Shared-exponent RGB texel format (9-bit mantissas, one 5-bit exponent: 32 bits a texel).
GL_RGB9_E5 = 0x8C3D


def create_gl_context(require: int = 430) -> Any:
    """Create a standalone headless OpenGL context of version ≥ *require*/100 (EGL backend).

    *require* is the moderngl version code (430 = OpenGL 4.3). Returns a ``moderngl.Context`` the
    caller releases; raises GLUnavailableError when moderngl or an EGL context is not available.
    """
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - moderngl is a dependency
        raise GLUnavailableError("moderngl is not installed") from exc
    try:
        ctx = moderngl.create_standalone_context(
            require=require,
            backend="egl",  # type: ignore[arg-type]  # moderngl's stub types **settings as dict values
        )
    except Exception as exc:  # moderngl raises plain Exception for EGL failures
        raise GLUnavailableError(f"no headless OpenGL {require / 100:.1f} context via EGL: {exc}") from exc
    prepare_context(ctx)
    return ctx


def prepare_context(ctx: Any) -> None:
    """Settings every moderngl context of the renderers takes (the core's standalone ones and the viewer's
    on Qt's context): seamless cube-map filtering, and the texture unit moderngl binds a texture to while
    it creates or writes one moved to the last combined unit. moderngl's default is unit 31, which a
    frame binds whenever the basis has four lobes or more (its shadow and light maps take units m + 11 to
    m + 27, :mod:`station.render.gl_frame_shadows`): a texture made or written in the middle of a frame
    would replace what the frame bound there."""
    ctx.enable_direct(GL_TEXTURE_CUBE_MAP_SEAMLESS)
    ctx.default_texture_unit = int(ctx.info["GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS"]) - 1


def gl_available() -> bool:
    """Whether a headless GL context can be created here (creates and releases one)."""
    try:
        ctx = create_gl_context()
    except GLUnavailableError:
        return False
    ctx.release()
    return True


def load_shader(name: str, defines: dict[str, object] | None = None) -> str:
    """Source of ``shaders/NAME`` with ``//#include`` lines expanded and *defines* injected."""
    path = SHADER_DIR / name
    if not path.is_file():
        raise RenderError(f"shader {name} not found in {SHADER_DIR}")
    lines = []
    for line in path.read_text().splitlines():
        if line.startswith("//#include "):
            lines.append(load_shader(line.split(maxsplit=1)[1].strip()))
        else:
            lines.append(line)
            if line.startswith("#version") and defines:
                lines.extend(f"#define {k} {v}" for k, v in defines.items())
    return "\n".join(lines)


def build_program(ctx: Any, vertex: str, fragment: str, defines: dict[str, object] | None = None) -> Any:
    """Compile and link a program from shader files; RenderError with the compiler log on failure."""
    try:
        return ctx.program(
            vertex_shader=load_shader(vertex, defines), fragment_shader=load_shader(fragment, defines)
        )
    except Exception as exc:
        raise RenderError(f"shader {vertex}+{fragment} failed to build: {exc}") from exc
