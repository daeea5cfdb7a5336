"""Whole lobe basis prefiltered from 1024×512 HDR environments, and its accuracy against brute force.

Run: ``.venv/bin/python -m bench.prefilter``. For each photographed environment in
``../shared/data/hdri`` (skipped when absent) and the procedural sky at 1024×512: the default basis
(``station.render.lobes.default_basis``) plus the diffuse map, GL engine, no cache, including context
creation and the equirect → cube pass. Baseline in the same run: the NumPy fallback engine for the
first environment (ratio); the NumPy engine's compiled loops (``station.render.prefilter_kernels``)
against its vectorised loops on the same maps (ratio; the grid sums equal to the last bit, the
brute-force sums' largest relative difference given). Accuracy: the GL tangent-grid quadrature against brute-force quadrature
over a 64² source cube (relative error of luminance per texel, at exponents 32 and 300).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from bench._report import Case, write_section
from station.model.colorimetry import REC709_LUMINANCE
from station.render import prefilter, procedural
from station.render.environment import load_environment
from station.render.lobes import default_basis

HDRI = Path(__file__).resolve().parents[2] / "shared" / "data" / "hdri"


def _accuracy(env, cases: list[Case]) -> None:
    src = env.downsampled(512).to_cube(64)
    with prefilter.GLPrefilter(src) as gl:
        for n in (32.0, 300.0):
            size = 16
            ref = prefilter.prefilter_brute(src, n, size) @ REC709_LUMINANCE
            got = gl.run(n, size, prefilter.sample_count(size)) @ REC709_LUMINANCE
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


def _loops(env, exps: tuple[float, ...], cases: list[Case]) -> None:
    """The NumPy engine's loops, compiled against vectorised, on *env*'s maps: every lobe of the basis
    by the grid quadrature (faces capped at 64, as the engine does), and the coat-transmitted diffuse map
    (brute force, 32² faces from a 64² source)."""
    from station.model.fresnel import ClearCoat

    src = env.to_cube(min(64, prefilter.source_size(env)))
    prefilter.prefilter_grid_numpy(src, 4.0, 8, 4)  # compile (or load the compiled loops) first
    plan = [(e, prefilter.output_size(e, src.shape[1])) for e in exps]
    timed: dict[bool, float] = {}
    maps: dict[bool, list[np.ndarray]] = {}
    for compiled in (True, False):
        t0 = time.perf_counter()
        maps[compiled] = [
            prefilter.prefilter_grid_numpy(src, e, size, prefilter.sample_count(size), compiled=compiled)
            for e, size in plan
        ]
        timed[compiled] = time.perf_counter() - t0
    same = all(np.array_equal(a, b) for a, b in zip(maps[True], maps[False], strict=True))
    note = f"{len(plan)} lobes, faces {[size for _, size in plan]}; equal to the last bit: {same}"
    cases.append(Case(f"NumPy grid quadrature, compiled, {env.name}", "", timed[True], "s", note))
    cases.append(Case(f"NumPy grid quadrature, vectorised, {env.name}", "", timed[False], "s"))
    cases.append(Case("grid quadrature: vectorised / compiled time", "", timed[False] / timed[True], "ratio"))
    coat = ClearCoat(1.5)
    for compiled in (True, False):
        t0 = time.perf_counter()
        maps[compiled] = [prefilter.prefilter_brute(src, 1.0, prefilter.COAT_DIFFUSE_SIZE, coat, compiled)]
        timed[compiled] = time.perf_counter() - t0
    diff = float(np.max(np.abs(maps[True][0] - maps[False][0]) / np.abs(maps[False][0])))
    cases.append(
        Case(
            f"coat diffuse map, brute force, compiled, {env.name}",
            f"6x{prefilter.COAT_DIFFUSE_SIZE}^2",
            timed[True],
            "s",
            f"from 6x{src.shape[1]}^2; largest relative difference to the vectorised sum {diff:.1e}",
        )
    )
    cases.append(Case(f"coat diffuse map, brute force, vectorised, {env.name}", "", timed[False], "s"))
    cases.append(Case("brute force: vectorised / compiled time", "", timed[False] / timed[True], "ratio"))


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
    _loops(envs[0], exps, cases)
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
