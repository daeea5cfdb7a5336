"""Accuracy on the demo library: the NumPy renderer's shading against ground truth, per paint class.

Run: ``.venv/bin/python -m bench.library_accuracy [--per-class N] [--envs NAME,...]``. A stratified sample
of the 6000-paint SYNTHETIC demo library (``station.formulate.demo``; seed 0, ``--per-class`` paints of
each class, 75 by default: 300 paints). This is the HELD-OUT split: the default basis was calibrated
(``bench.library_basis``) on a disjoint training split drawn from the library's other paints, so the
figures are not measured on the paints it was tuned on. Classes:

* ``solid``: library type solid; ``pearl``: type pearl;
* ``bright silver``: metallic with face L* ≥ 80 and face chroma < 10 (the first angle, 15°);
* ``coloured metallic``: the other metallics.

Each paint is fitted to the model (``station.model.fit.fit_fftg_batch`` through its five measured angles;
paints without a fit are counted and left out), its lobe weights fitted with the shipped default basis
(:func:`station.render.lobes.default_basis`, ``perceptual`` fit), and shaded on an orthographic sphere (32 × 32, rim excluded) by
``numpy_renderer.shade_pixels`` (GL-prefiltered maps where GL runs, lights extracted and smoothed
over their spread, ``lut`` horizon)
against :class:`station.render.truth.TruthScene` (the designed BRDF integrated). Environments: the
procedural ones and every HDR of ``../shared/data/hdri``, 512 wide (as ``bench.env_accuracy``).
ΔE: CIEDE2000 per pixel, Lab relative to the scene's white; mean and 95th percentile over the pixels of
each class. Bars (the issue's): per class and environment mean ≤ 1.0 and p95 ≤ 2.3.

Baseline, same run: the radiance-weighted fit (``auto``, eq 2.4.2 as printed) on the same pixels.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from bench._report import Case, bench_parser, write_section
from bench.env_accuracy import MEAN_BAR, P95_BAR, SPHERE, environments, ndv_of, reflect_of
from station.formulate.demo import demo_library
from station.formulate.library import Library
from station.model import FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.model.errors import FitError
from station.model.fit import fit_fftg_batch
from station.render import lobe_fit as lf
from station.render import numpy_renderer as nr
from station.render import truth as tr
from station.render.lobes import default_basis
from station.render.prefilter import prefilter_basis

CLASSES = ("solid", "coloured metallic", "pearl", "bright silver")
SEED = 0


def classify(types: np.ndarray, face_lab: np.ndarray) -> np.ndarray:
    """Class name per paint (module docstring)."""
    chroma = np.hypot(face_lab[:, 1], face_lab[:, 2])
    silver = (types == "metallic") & (face_lab[:, 0] >= 80.0) & (chroma < 10.0)
    return np.where(
        types == "solid",
        "solid",
        np.where(types == "pearl", "pearl", np.where(silver, "bright silver", "coloured metallic")),
    )


#: Paints per class the held-out (test) sample is drawn from; the training split never holds them.
TEST_PER_CLASS = 75
#: Seed of the training split (``bench.library_basis`` calibrates the basis on it).
TRAIN_SEED = 1


def _library_rows(per_class: int, split: str) -> tuple[Library, np.ndarray, list[tuple[str, np.ndarray]]]:
    """(library, its classes, [(class, rows)]) of a split: ``test`` draws TEST_PER_CLASS rows per class with
    SEED and keeps the first *per_class*; ``train`` draws *per_class* with TRAIN_SEED from the rest."""
    if split not in ("test", "train"):
        raise ValueError(f"split: 'test' or 'train', not {split!r}")
    lib = demo_library()
    order = np.argsort(lib.angles_deg)
    cls = classify(np.asarray(lib.types), lib.lab[:, order][:, 0])
    test_rng, train_rng = np.random.default_rng(SEED), np.random.default_rng(TRAIN_SEED)
    out = []
    for name in CLASSES:
        rows = np.flatnonzero(cls == name)
        test = test_rng.choice(rows, size=min(TEST_PER_CLASS, rows.size), replace=False)
        if split == "test":
            pick = test[:per_class]
        else:
            rest = np.setdiff1d(rows, test)
            pick = train_rng.choice(rest, size=min(per_class, rest.size), replace=False)
        out.append((name, np.sort(pick)))
    return lib, cls, out


def sample_paints(per_class: int, split: str = "test") -> tuple[list[FaceFlopTravelGloss], list[str], int]:
    """(designs, their classes, paints without a fit) of a stratified sample of the demo library: the
    held-out ``test`` split this benchmark reports on, or the disjoint ``train`` split the shipped basis
    was calibrated on (:func:`_library_rows`)."""
    lib, _, picks = _library_rows(per_class, split)
    order = np.argsort(lib.angles_deg)
    angles = tuple(float(lib.angles_deg[j]) for j in order)
    lab = lib.lab[:, order]
    designs: list[FaceFlopTravelGloss] = []
    names: list[str] = []
    failed = 0
    for name, pick in picks:
        batch = fit_fftg_batch(angles, lab[pick], lib.gloss_gu[pick])
        for n in range(len(batch)):
            try:
                designs.append(batch.result(n).design)
                names.append(name)
            except FitError:  # a paint without a model fit is counted, not shaded
                failed += 1
    return designs, names, failed


def class_errors(
    env, designs: list[FaceFlopTravelGloss], reports: dict[str, lf.FitReport]
) -> dict[str, np.ndarray]:
    """ΔE00 (designs, pixels) of each fit against the truth in *env*."""
    normals, views = tr.sphere_pixels(SPHERE)
    scene = tr.TruthScene(env, normals, views)
    white = float(scene.white()[..., 1].max())
    brdfs = [lf.designed_brdf(d) for d in designs]
    pb = prefilter_basis(env, default_basis().exponents, engine="auto")
    ndv, refl = ndv_of(normals, views), reflect_of(normals, views)
    out: dict[str, np.ndarray] = {}
    refs = [linear_srgb_to_lab(scene.truth(b) / white) for b in brdfs]
    for key, rep in reports.items():
        out[key] = np.stack(
            [
                delta_e(
                    ref,
                    linear_srgb_to_lab(
                        nr.shade_pixels(pb, rep.weights(i), normals, refl, ndv, horizon="lut") / white
                    ),
                    "cie2000",
                )
                for i, ref in enumerate(refs)
            ]
        )
    return out


def _arguments(argv: list[str] | None) -> argparse.Namespace:
    """The command line, parsed before anything is measured (``--help`` prints the module's doc)."""
    ap = bench_parser(__doc__, "library_accuracy")
    ap.add_argument("--per-class", type=int, default=75)
    ap.add_argument("--envs", default="", help="comma-separated environment names (default: all)")
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = _arguments(argv)
    designs, names, failed = sample_paints(args.per_class)
    targets = lf.targets_from_brdfs([lf.designed_brdf(d) for d in designs])
    reports = {
        "perceptual": lf.fit_targets(targets),
        "auto (baseline)": lf.fit_targets(targets, method="auto"),
    }
    envs = environments()
    if args.envs:
        wanted = set(args.envs.split(","))
        envs = [e for e in envs if e.name in wanted]
    cls = np.array(names)
    counts = ", ".join(f"{c} {int((cls == c).sum())}" for c in CLASSES)
    print(f"{len(designs)} paints ({counts}); {failed} without a model fit", flush=True)
    cases: list[Case] = []
    for env in envs:
        t0 = time.perf_counter()
        errs = class_errors(env, designs, reports)
        for key, de in errs.items():
            for c in CLASSES:
                d = de[cls == c]
                if d.size == 0:
                    continue
                mean, p95 = float(d.mean()), float(np.percentile(d, 95.0))
                ok = "meets" if mean <= MEAN_BAR and p95 <= P95_BAR else "MISSES"
                print(f"{env.name:16s} {key:16s} {c:18s} mean {mean:5.2f}  p95 {p95:5.2f}  {ok}", flush=True)
                size = f"{int((cls == c).sum())} paints"
                cases.append(
                    Case(f"{env.name} {key} {c}: mean", size, mean, "ΔE00", f"p95 {p95:.2f}; {ok} bar")
                )
        print(f"{env.name}: {time.perf_counter() - t0:.1f} s", flush=True)
    setup = (
        f"{len(designs)} paints ({counts}); {failed} without a model fit. Bars per class and environment: "
        f"mean ≤ {MEAN_BAR}, p95 ≤ {P95_BAR} (CIEDE2000). Baseline in the same run: the radiance-weighted fit "
        "(`auto`)."
    )
    write_section(
        "library_accuracy", "Accuracy on the demo library (bench/library_accuracy.py)", cases, setup
    )


if __name__ == "__main__":
    main()
