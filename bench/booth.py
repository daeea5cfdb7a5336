"""Light booth: an illuminant switch from cached basis images, against the cold first picture.

Run: ``.venv/bin/python -m bench.booth [--size N]``. Paints: a metameric pair made from the library silver
(``station.model.booth.metameric_pair``, equal under D65, different under A). Per shape (panels, seam,
car), the cold case is the first picture in a fresh :class:`station.render.booth.BoothRenderer` sharing
the prefiltered booth (basis images: NumPy ray casting, or GL probes for the car), then the switch cycles
D65 → A → F11 → TL84 → LED-B4 → D65 … (two design fits per illuminant, one weighted sum, tint, tone map)
and reports the median and worst. The bar is 0.5 s per switch on llvmpipe (issue 29). The prefiltered
booth itself is built once and reported on its own line (it is cached on disk across runs).
"""

from __future__ import annotations

import time

import numpy as np

from bench._report import Case, bench_parser, write_section
from station.model.booth import BOOTH_SHAPES, metameric_pair
from station.model.domain import ANGLES_5
from station.model.examples import SILVER
from station.model.spectra import reflectance_from_lab
from station.render.booth import BOOTH_SIZE, BoothPaint, BoothRenderer

ANGLES = ANGLES_5
CYCLE = ("D65", "A", "F11", "TL84", "LED-B4")
SWITCHES = 20


def _pair() -> tuple[BoothPaint, BoothPaint]:
    std, smp = metameric_pair(reflectance_from_lab(SILVER.lab_at(ANGLES)), strength=0.3)
    return BoothPaint(ANGLES, std, SILVER.gloss_gu, "standard"), BoothPaint(
        ANGLES, smp, SILVER.gloss_gu, "trial"
    )


def main() -> None:
    ap = bench_parser(__doc__, "booth")
    ap.add_argument(
        "--size", type=int, default=BOOTH_SIZE, help=f"picture side in pixels (default {BOOTH_SIZE})"
    )
    args = ap.parse_args()
    size = args.size
    std, smp = _pair()
    t0 = time.perf_counter()
    basis = BoothRenderer(size).basis
    cases = [Case("prefiltered booth (disk cache)", "256 px env", time.perf_counter() - t0, "s")]
    for shape in BOOTH_SHAPES:
        r = BoothRenderer(size, basis=basis)  # the cold case: the shape's basis images and the first frame
        t0 = time.perf_counter()
        r.frame(std, smp, "D65", shape=shape)
        cold = time.perf_counter() - t0
        times = []
        for k in range(SWITCHES):
            t0 = time.perf_counter()
            r.frame(std, smp, CYCLE[(k + 1) % len(CYCLE)], shape=shape)
            times.append(time.perf_counter() - t0)
        med = float(np.median(times))
        px = f"{size}x{size}"
        cases += [
            Case(f"{shape}: cold first picture (baseline)", px, cold * 1e3, "ms", "basis images + frame"),
            Case(
                f"{shape}: illuminant switch, median",
                px,
                med * 1e3,
                "ms",
                f"bar <= 500 ms; {cold / med:.0f}x faster",
            ),
            Case(f"{shape}: illuminant switch, worst", px, max(times) * 1e3, "ms", f"{SWITCHES} switches"),
        ]
    write_section(
        "booth",
        "Light booth: illuminant switch (bench/booth.py)",
        cases,
        "An illuminant switch refits both designs under the new illuminant and recombines the cached basis "
        "images of the shape; the cold case builds those images (docs/booth.md).",
    )


if __name__ == "__main__":
    main()
