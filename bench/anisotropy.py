"""Anisotropic Ward (eqs 2.5.4–2.5.7): CIEDE2000 of the sampled reconstruction against ground truth, per
sample count, with the failure region of the accuracy bar (mean ≤ 1.0, p95 ≤ 2.3) charted.

Run: ``.venv/bin/python -m bench.anisotropy``. For each case of ``station.reproduce.ch2_aniso.ANISO_CASES``
(mild and strong anisotropy in the light booth; strong under one point light, the thesis's Fig. 2.10)
the off-specular sum of eq 2.5.7 (``station.render.anisotropy.shade_anisotropic``, which the GL shader
matches to < 0.1 ΔE00, tests/render/test_anisotropy.py) is rendered with J = 1 … 81 samples and
compared, tone mapped, with the brute-force integral of eq 2.5.4 over the environment. One line per case
and sample count; the baseline measured in the same run is J = 1 (eq 2.5.5: the isotropic α_x lobe at
the mirror direction), each line giving err(J) / err(1). The same data is ``station reproduce --figure
2.10``. Writes docs/render-anisotropy-samples.png.
"""

from __future__ import annotations

from bench._report import REPORT, Case, bench_cli, write_section
from station.reproduce import ch2_aniso as ch2

CHART = REPORT.parent / "render-anisotropy-samples.png"


def main() -> None:
    sweeps = ch2.anisotropy_sweeps()
    cases = []
    for name, lobe, s in sweeps:
        base_mean, base_p95 = s.mean_de[0], s.p95_de[0]
        for j, mean, p95 in zip(s.samples, s.mean_de, s.p95_de, strict=True):
            meets = mean <= ch2.MEAN_BAR and p95 <= ch2.P95_BAR
            cases.append(
                Case(
                    f"{name}, J = {j}",
                    f"α {lobe.alpha_x:g}/{lobe.alpha_y:g}",
                    mean,
                    "mean ΔE00",
                    f"p95 {p95:.2f}; ratio to J = 1: mean {mean / base_mean:.2f}, p95 {p95 / base_p95:.2f}; "
                    + ("meets" if meets else "fails")
                    + " the bar",
                )
            )
    ch2.plot_anisotropy_samples(CHART, sweeps)
    summary = "\n".join(
        f"* {name}: settles (mean within 0.1 of 81 samples) at J = {s.converged()}; "
        + (
            f"meets the bar from J = {s.meets(ch2.MEAN_BAR, ch2.P95_BAR)}"
            if s.meets(ch2.MEAN_BAR, ch2.P95_BAR) is not None
            else f"never meets the bar (floor mean {s.mean_de[-1]:.2f}, p95 {s.p95_de[-1]:.2f})"
        )
        + f" ({s.seconds:.0f} s)"
        for name, _, s in sweeps
    )
    write_section(
        "anisotropy",
        "Anisotropic Ward: error against off-specular samples",
        cases,
        f"Sphere {ch2.SWEEP_SIZE}², truth cube {ch2.SWEEP_TRUTH_FACE}², NumPy reference renderer.\n\n"
        + summary
        + "\n\n![error against samples](render-anisotropy-samples.png)",
    )


if __name__ == "__main__":
    bench_cli(__doc__, "anisotropy")
    main()
