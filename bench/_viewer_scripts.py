"""Scripts the viewer benchmark (:mod:`bench.viewer`) runs in fresh interpreters (``python -c``): the core
renderer's orbit on an EGL context without Qt (the baseline) and the viewer's start-up to its first frame."""

from __future__ import annotations

import textwrap

#: argv: size, frames, prefilter engine ("gl" | "numpy"), orbit environment, view flags (comma-separated;
#: ``model``: the procedural car instead of the sphere), today's renderer (1) or the one before its
#: fragment savings (0: ``GLRenderer.footprint`` and ``mesh_prepass`` False). Prints ``CORE`` median, best
#: and CPU per frame, then the sky's prefilter + first frame wall and CPU (s).
CORE_ORBIT = textwrap.dedent("""
    import time, sys
    from station.model.design_io import default_flakes
    from station.render.gl_renderer import GLRenderer, create_gl_context
    from station.render.scene_image import builtin_mesh
    from ui.models.document import DEFAULT_DESIGN
    from ui.models.view import ViewSettings, environment_basis, environment_basis_gl, paint_weights
    size, n, engine, orbit_env = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4]
    flags = {k: True for k in sys.argv[5].split(",") if k}
    model = "car" if flags.pop("model", False) else None
    mesh = builtin_mesh(model) if model else None
    today = sys.argv[6] == "1"
    w = paint_weights(DEFAULT_DESIGN)
    ctx = create_gl_context()
    t0, c0 = time.perf_counter(), time.process_time()
    basis = environment_basis_gl("sky", ctx) if engine == "gl" else environment_basis("sky")
    with GLRenderer(basis, size, size, ctx=ctx) as gl:
        gl.render(ViewSettings(environment="sky").scene(), [w, w])
        t_env, c_env = time.perf_counter() - t0, time.process_time() - c0
    flakes = default_flakes(DEFAULT_DESIGN) if flags.get("flakes") else None
    with GLRenderer(environment_basis_gl(orbit_env, ctx), size, size, ctx=ctx) as gl:
        gl.footprint = gl.mesh_prepass = today
        ts = []
        c1 = 0.0
        for i in range(n + 2):
            st = ViewSettings(environment=orbit_env, yaw_deg=3.0 * (i + 1), model=model, **flags)
            sc = st.scene()
            if i == 2:
                c1 = time.process_time()
            t = time.perf_counter()
            if mesh is None:
                gl.render(sc, [w, w], st.exposure_ev, coat=st.clear_coat(), flakes=flakes)
            else:
                gl.render_mesh(mesh, [w, w], sc.view_camera, sc.stage, st.clear_coat(), st.exposure_ev,
                               flakes=flakes)
            ts.append(time.perf_counter() - t)
        cpu = (time.process_time() - c1) / n
    ts = sorted(ts[2:])
    print(f"CORE {ts[len(ts) // 2]:.6f} {ts[0]:.6f} {cpu:.6f} {t_env:.4f} {c_env:.4f}", flush=True)
""")

#: Prints ``FIRST_FRAME`` first frame, import time, the view's class and full-quality frame (s).
STARTUP = textwrap.dedent("""
    import time
    t0 = time.perf_counter()
    import sys
    from ui.widgets.render_view import configure_default_format
    configure_default_format()
    from PySide6.QtWidgets import QApplication
    app = QApplication([])
    from ui.app import MainWindow
    t_imp = time.perf_counter() - t0
    win = MainWindow(ask_on_close=False)
    win.resize(1500, 950)
    view = win.view_panel.view
    win.show()
    while view.frames == 0:
        app.processEvents()
    t_first = time.perf_counter() - t0
    while not view.full_quality:
        app.processEvents()
        time.sleep(0.002)
    view.wait_idle()
    print(f"FIRST_FRAME {t_first:.4f} {t_imp:.4f} {type(view).__name__} {time.perf_counter() - t0:.4f}",
          flush=True)
    win.close()
    app.shutdown()
""")
