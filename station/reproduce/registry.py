"""The registry of thesis experiments, in thesis order, and the runner behind ``station reproduce``."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from pathlib import Path

from station.reproduce.core import Experiment, ExperimentResult
from station.reproduce.errors import ReproduceInputError


def _lazy(module: str, function: str) -> Callable[[Path | None], ExperimentResult]:
    """``station.reproduce.<module>.<function>``, imported on first call (selecting stays cheap)."""

    def run(out_dir: Path | None) -> ExperimentResult:
        import importlib

        fn: Callable[[Path | None], ExperimentResult] = getattr(
            importlib.import_module(f"station.reproduce.{module}"), function
        )
        return fn(out_dir)

    run.__name__ = f"{module}.{function}"
    return run


#: Every experiment ``station reproduce`` runs; ``slow`` ones take tens of seconds or more.
EXPERIMENTS: tuple[Experiment, ...] = (
    Experiment(
        "ch2-basis",
        "2",
        "Basis exponents and errors for 1–11 lobes (eq 2.3.4)",
        ("2.4", "2.5"),
        _lazy("ch2", "basis_table"),
        slow=True,
    ),
    Experiment(
        "ch2-basis-quick",
        "2",
        "Basis search, 1–2 lobes, against the shipped table",
        ("2.4", "2.5"),
        _lazy("ch2", "basis_quick"),
        quick_of="ch2-basis",
    ),
    Experiment(
        "ch2-fit-methods",
        "2",
        "Lobe-weight fit: the thesis's LP, NNLS, clamped least squares (§2.4)",
        ("§2.4",),
        _lazy("ch2", "fit_methods"),
    ),
    Experiment(
        "ch2-fig2.10",
        "2",
        "Anisotropic reconstruction against off-specular samples, vs ground truth (§2.5.3)",
        ("2.10",),
        _lazy("ch2_aniso", "fig210"),
        slow=True,
    ),
    Experiment(
        "ch2-fig2.10-quick",
        "2",
        "Anisotropic reconstruction against samples, coarse sweep",
        ("2.10",),
        _lazy("ch2_aniso", "fig210_quick"),
        quick_of="ch2-fig2.10",
    ),
    Experiment(
        "ch2-frame-rates",
        "2",
        "Lobe renderer frame rates for 5 / 9 / 31 / 81 anisotropic samples, as ratios (§2.5.3)",
        ("§2.5.3",),
        _lazy("ch2_aniso", "frame_rates"),
    ),
    Experiment(
        "ch3-representations",
        "3",
        "Representations and conversions (§3.3, eqs 3.3.1–3.3.10)",
        ("3.3",),
        _lazy("ch3", "representations"),
    ),
    Experiment(
        "ch3-hsb",
        "3",
        "Hue / saturation / brightness group edit (§3.4.2)",
        ("§3.4.2",),
        _lazy("ch3", "hsb"),
    ),
    Experiment(
        "ch3-variations",
        "3",
        "Variations ring (§3.4.4): one step = the degree",
        ("3.9", "3.10"),
        _lazy("ch3", "variations_ring"),
    ),
    Experiment(
        "ch3-tweaker",
        "3",
        "Tweaker blend (eq 3.6.4 with erratum 1) and crosshair drags (§3.6)",
        ("3.6",),
        _lazy("ch3", "tweaker"),
    ),
    Experiment(
        "ch3-fig3.20",
        "3",
        "Sketch fit (Fig. 3.20) with the RMS of an independent re-render; contrast gloss vs art gloss",
        ("3.20", "§3.5.3"),
        _lazy("ch3_sketch", "fig320"),
        slow=True,
    ),
    Experiment(
        "ch3-traced",
        "3",
        "Traced, marker-filled art (Fig. 3.21): re-render RMS",
        ("3.21",),
        _lazy("ch3_sketch", "traced_art"),
    ),
    Experiment(
        "ch3-environment-fit",
        "3",
        "Environment-lit sketch fit (§3.7.5): time and re-render RMS",
        ("3.19", "3.7"),
        _lazy("ch3_sketch", "environment_fit"),
    ),
    Experiment(
        "ch4-lambertian",
        "4",
        "Lambertian goniogeometric index vs its closed form (§4.3.2)",
        ("4.3",),
        _lazy("ch4", "lambertian_index"),
    ),
    Experiment(
        "ch4-fig4.3",
        "4",
        "Goniogeometric index read off the seam-ΔE curves (Fig. 4.3)",
        ("4.3",),
        _lazy("ch4", "fig43"),
    ),
    Experiment(
        "ch4-fig4.4", "4", "Inverse trompe l'oeil for a solid (Fig. 4.4)", ("4.4",), _lazy("ch4", "fig44")
    ),
    Experiment(
        "ch4-figs4.5-4.7",
        "4",
        "Metallic inverse trompe l'oeil (Figs 4.5–4.7)",
        ("4.5", "4.6", "4.7"),
        _lazy("ch4", "figs45_47"),
    ),
    Experiment(
        "ch5-library",
        "5",
        "Library statistics (Fig. 5.4, §5.3.4)",
        ("5.3", "5.4"),
        _lazy("ch5", "library_statistics"),
    ),
    Experiment(
        "ch5-indices",
        "5",
        "Index examples GM044, YM144, BM304, GM027 (Figs 5.5–5.8)",
        ("5.5", "5.6", "5.7", "5.8"),
        _lazy("ch5", "index_examples"),
    ),
    Experiment(
        "ch5-colorsnap",
        "5",
        "ColorSnap on 6000 paints in real time (§5.3.5)",
        ("5.9",),
        _lazy("ch5", "colorsnap_timing"),
    ),
    Experiment(
        "ch5-fig5.10",
        "5",
        "ColorSnap warnings for a too-saturated and an off-radial design (Fig. 5.10)",
        ("5.10",),
        _lazy("ch5", "snap_warnings_fig510"),
    ),
    Experiment(
        "gloss-meter",
        "gloss",
        "Simulated gloss meter at 20/60/85° vs clear coats",
        ("gloss",),
        _lazy("gloss", "meter_geometries"),
    ),
)


def _norm(figure_id: str) -> str:
    """``"Fig. 4.4"``, ``"fig 4.4"`` and ``"4.4"`` name the same figure (a section keeps its ``§``)."""
    f = figure_id.strip().lower()
    for prefix in ("figure", "fig.", "fig"):
        if f.startswith(prefix):
            f = f[len(prefix) :].strip()
    return f


def select(figure: str | None = None, include_slow: bool = True) -> tuple[Experiment, ...]:
    """The experiments reproducing thesis figure *figure* (e.g. ``"4.4"``, ``"§2.4"``, or an experiment key).

    With *include_slow*, a quick variant is left out when its slow experiment runs. Raises
    :class:`ReproduceInputError` naming the accepted ids when nothing matches.
    """
    want = None if figure is None else _norm(figure)
    chosen = [
        e
        for e in EXPERIMENTS
        if (include_slow or not e.slow)
        and (want is None or want == e.key or want in {_norm(f) for f in e.figures})
    ]
    keys = {e.key for e in chosen}
    chosen = [e for e in chosen if not (e.quick_of and e.quick_of in keys)]
    if figure is not None and not chosen:
        ids = sorted({f for e in EXPERIMENTS for f in e.figures} | {e.key for e in EXPERIMENTS})
        raise ReproduceInputError("figure", "one of " + ", ".join(ids), figure)
    return tuple(chosen)


def run(
    experiments: Iterable[Experiment],
    out_dir: Path | None,
    progress: Callable[[Experiment], None] | None = None,
) -> list[ExperimentResult]:
    """Run *experiments* in order; PNGs go to *out_dir* (``None``: no pictures)."""
    results = []
    for e in experiments:
        if progress is not None:
            progress(e)
        t0 = time.perf_counter()
        r = e.run(out_dir)
        results.append(
            ExperimentResult(
                r.experiment, r.quantities, r.figures, r.notes, time.perf_counter() - t0, r.extra
            )
        )
    return results
