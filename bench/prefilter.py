"""Whole lobe basis prefiltered from 1024×512 HDR environments, and its accuracy against brute force.

Run: ``.venv/bin/python -m bench.prefilter``. For each photographed environment in
``../shared/data/hdri`` (skipped when absent) and the procedural sky at 1024×512: the default basis
(``station.render.lobes.default_basis``) plus the diffuse map, GL engine, no cache, including context
creation and the equirect → cube pass. Baseline in the same run: the NumPy fallback engine for the
first environment (ratio). Accuracy: the GL tangent-grid quadrature against brute-force quadrature
over a 64² source cube (relative error of luminance per texel, at exponents 32 and 300).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from bench._report import Case, write_section
from station.render import prefilter, procedural
from station.render.environment import load_environment
from station.render.lobes import default_basis

HDRI = Path(__file__).resolve().parents[2] / "shared" / "data" / "hdri"
LUM = np.array([0.2126, 0.7152, 0.0722])


def _accuracy(env, cases: list[Case]) -> None:
    src = env.downsampled(512).to_cube(64)
    with prefilter.GLPrefilter(src) as gl:
        for n in (32.0, 300.0):
            size = 16
            ref = prefilter.prefilter_brute(src, n, size) @ LUM
            got = gl.run(n, size, prefilter.sample_count(size)) @ LUM
            rel = np.abs(got - ref) / ref
            cases.append(
                Case(
                    f"GL vs brute force, n={n:g}, {env.name}",
                    "6x16x16",
                    float(np.median(rel)),
                    "median rel",
                    f"95th pct {np.percentile(rel, 95):.3f}",
                )
            )


def main() -> None:
    exps = default_basis().exponents
    envs = [load_environment(p) for p in sorted(HDRI.glob("*.hdr")) + sorted(HDRI.glob("*.exr"))]
    envs.append(procedural.sunny_sky(1024))
    cases: list[Case] = []
    for env in envs:
        times, cpu = [], []
        for _ in range(3):
            t0, c0 = time.perf_counter(), time.process_time()
            basis = prefilter.prefilter_basis(env, exps, engine="gl")
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
        cases.append(
            Case(
                f"whole basis, GL, {env.name}",
                f"{env.equirect.shape[1]}x{env.height}",
                float(np.median(times)),
                "s",
                f"bar <= 1.5 s; {len(exps)} lobes + diffuse; best {min(times):.2f} s; "
                f"process CPU {np.median(cpu):.2f} s; faces {[c.shape[1] for c in basis.cubes]}",
            )
        )
    t0 = time.perf_counter()
    prefilter.prefilter_basis(envs[0], exps, engine="numpy")
    t_np = time.perf_counter() - t0
    cases.append(Case(f"whole basis, NumPy fallback, {envs[0].name}", "", t_np, "s", "faces capped at 64"))
    cases.append(Case("NumPy / GL time", "", t_np / cases[0].figure, "ratio"))
    _accuracy(envs[0], cases)
    write_section(
        "prefilter",
        "Environment prefiltering (station.render.prefilter)",
        cases,
        f"Exponents: {', '.join(f'{e:g}' for e in exps)}. Load average at the end: "
        f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs (the machine is shared).",
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "prefilter")
    main()
