"""The figures of docs/render.md's "Three paints, two cars, three environments" section, made through the
product's public interfaces: the paints come from the demo library by code (``demo_library``,
``fit_fftg``, ``save_design``), every picture from the ``station render`` command line in a subprocess.

Run: ``python scripts/render_figures.py`` (no arguments). The CC0 car and the HDR are read from
``meshes/*.glb`` and ``hdri/*.hdr`` of the ``shared/data`` folder beside the checkout (not part of the
repository; ``--shared DIR`` points elsewhere). Writes into ``docs/render/``:

* ``paints-sheet.png``: three paints × two models (the procedural car, a CC0 car) × three environments
  (booth, sunny sky, a photographed HDR), on the stage with the clear coat and the paint's flakes;
* ``paints-flakes.png``: flakes off | on, far (the default view) and close (``--view``), in the sky;
* ``paints-error.png``: GL against the ground truth on the sphere, ΔE00 per pixel with a colour bar,
  mean and p95 in each title (``--engine truth`` and ``--engine gl --aa 1``, scene-linear outputs).

It prints one progress line per picture, the numbers the captions quote (ΔE00 mean / p95, the flakes'
level of detail, the flakes' 16 × 16 block means) and the run's wall and CPU time. Deterministic: no
random draw, no time budget. Not a test or a benchmark: the suite never runs it.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "render"
SHARED = ROOT.parent / "shared" / "data"

#: The paints (demo library code, caption): a bright silver, a red metallic and a blue pearl.
PAINTS: tuple[tuple[str, str], ...] = (
    ("SYN-NM0001", "bright silver"),
    ("SYN-RM0229", "red metallic"),
    ("SYN-BP0012", "blue pearl"),
)
#: The photographed HDR of the sheets (first match in ``hdri/``), and the CC0 car (``meshes/``).
HDR_NAME = "spruit_sunrise"
CAR_NAME = "car-sport"
#: Tile size (pixels) of the contact and flake sheets, and of the error maps.
TILE = 200
ERROR_SIZE = 256
#: Close-up of ``station render --view YAW,PITCH,DISTANCE`` (the default mesh view: about 30.5, 16, 4.7).
CLOSE_VIEW = "30,15,2.0"
#: Clear-coat index of the sheets (``--coat``).
COAT = "1.5"
#: Upper end of the error maps' colour bar (ΔE00).
DE_MAX = 5.0
#: Sphere size (pixels) whose brightest white-Lambertian pixel is the Lab white of the ΔE00 numbers.
WHITE_SIZE = 16
#: Side (pixels) of the blocks whose mean colour the flakes must keep.
BLOCK = 16


@dataclass
class Figures:
    """What the captions state: markdown table rows per figure (filled while the figures are made)."""

    paints: list[str] = field(default_factory=list)
    sheet_flakes: dict[str, str] = field(default_factory=dict)
    flakes: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)


@dataclass
class Progress:
    """One line per step: ``[k/n] what (elapsed s)``."""

    total: int
    done: int = 0
    start: float = 0.0

    def step(self, what: str) -> None:
        self.done += 1
        print(f"[{self.done:3d}/{self.total}] {what} ({time.perf_counter() - self.start:5.1f} s)", flush=True)


def _design_files(folder: Path, figures: Figures) -> dict[str, Path]:
    """Design files of PAINTS fitted from the demo library's five angles (public API)."""
    from station.formulate.demo import demo_library
    from station.model import AspecularMeasurements, fit_fftg
    from station.model.design_io import default_flakes, save_design

    lib = demo_library()
    files: dict[str, Path] = {}
    for code, _ in PAINTS:
        paint = lib.paint(lib.index_of(code))
        order = np.argsort(paint.angles_deg)
        meas = AspecularMeasurements(
            tuple(float(paint.angles_deg[i]) for i in order), np.asarray(paint.lab)[order], paint.gloss_gu
        )
        fit = fit_fftg(meas)
        design = replace(fit.design, name=code)
        files[code] = save_design(design, folder / f"{code}.json")
        layer = default_flakes(design)
        flakes = (
            "none"
            if layer is None
            else (f"{layer.size_um:g} µm, {layer.density_per_mm2:g}/mm², {layer.spread_deg:g}°")
        )
        figures.paints.append(
            f"| {code} | {dict(PAINTS)[code]} | {paint.type} | "
            + " / ".join(f"{x:.1f}" for x in design.face)
            + " | "
            + " / ".join(f"{x:.1f}" for x in design.flop)
            + f" | {design.travel_deg:.0f}° | {paint.gloss_gu:.0f} GU | {flakes} | "
            + f"{float(np.max(fit.residual_de)):.2f} |"
        )
    return files


def _render(
    progress: Progress, what: str, args: list[str], out: Path, linear: bool = False
) -> dict[str, Any]:
    """``station render ARGS --out OUT --json`` in a subprocess; its JSON report (``linear``: also a .npy)."""
    cmd = [sys.executable, "-m", "station.cli", "render", *args, "--out", str(out), "--json"]
    if linear:
        cmd += ["--linear-out", str(out.with_suffix(".npy"))]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    if proc.returncode != 0:
        raise SystemExit(f"station render failed ({what}): {proc.stderr.strip() or proc.stdout.strip()}")
    progress.step(what)
    report: dict[str, Any] = json.loads(proc.stdout)
    return report


def _font(size: int) -> Any:
    from PIL import ImageFont

    return ImageFont.load_default(size=size)


def _labelled_grid(tiles: list[list[Path]], col_labels: list[str], row_labels: list[str], title: str) -> Any:
    """PIL image of *tiles* (rows × columns of PNG paths) with a title, column and row labels."""
    from PIL import Image, ImageDraw

    left, top, head = 150, 46, 24
    rows, cols = len(tiles), len(tiles[0])
    sheet = Image.new("RGB", (left + cols * TILE, top + head + rows * TILE), "white")
    draw = ImageDraw.Draw(sheet)
    draw.text((6, 6), title, fill="black", font=_font(15))
    for c, text in enumerate(col_labels):
        for k, line in enumerate(text.split("\n")):
            draw.text((left + c * TILE + 4, top - 12 + 13 * k), line, fill="black", font=_font(12))
    for r, text in enumerate(row_labels):
        for k, line in enumerate(text.split("\n")):
            draw.text((6, top + head + r * TILE + 8 + 16 * k), line, fill="black", font=_font(13))
        for c in range(cols):
            with Image.open(tiles[r][c]) as im:
                sheet.paste(im.convert("RGB"), (left + c * TILE, top + head + r * TILE))
    return sheet


def _lab(linear: np.ndarray, white: float) -> np.ndarray:
    from station.model.colorimetry import linear_srgb_to_lab

    return np.asarray(linear_srgb_to_lab(np.asarray(linear, np.float64) / white))


def _block_means_de(off: np.ndarray, on: np.ndarray, white: float) -> tuple[float, int]:
    """(p95 ΔE00, count) of the BLOCK × BLOCK block means flakes on against off, over the blocks the
    flakes touch (at least half of their pixels changed: the painted blocks)."""
    from station.model.difference import delta_e

    h, w = (off.shape[0] // BLOCK) * BLOCK, (off.shape[1] // BLOCK) * BLOCK

    def blocks(a: np.ndarray) -> np.ndarray:
        return a[:h, :w].reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, -1).mean(axis=(1, 3))

    changed = blocks((np.abs(on - off).max(axis=-1) > 0)[..., None].astype(np.float64))[..., 0] >= 0.5
    if not changed.any():
        return 0.0, 0
    de = np.asarray(delta_e(_lab(blocks(off), white), _lab(blocks(on), white), "cie2000"))[changed]
    return float(np.percentile(de, 95)), int(changed.sum())


def _white(env_arg: str) -> float:
    """The brightest white-Lambertian luminance of *env_arg* on a WHITE_SIZE² sphere (the Lab white of the ΔE maps,
    as the accuracy benchmarks take it)."""
    from station.render.environment import load_environment
    from station.render.numpy_renderer import gbuffer
    from station.render.procedural import procedural_environment
    from station.render.shapes import Scene
    from station.render.truth import TruthScene

    env = load_environment(env_arg) if Path(env_arg).suffix else procedural_environment(env_arg)
    g = gbuffer(Scene("sphere"), WHITE_SIZE, WHITE_SIZE)
    return float(TruthScene(env, g.normal[g.mask], g.view[g.mask]).white()[..., 1].max())


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--shared", type=Path, default=SHARED, help="folder with meshes/*.glb and hdri/*.hdr")
    args = parser.parse_args(argv)
    hdrs = sorted((args.shared / "hdri").glob(f"{HDR_NAME}*.hdr"))
    cars = sorted((args.shared / "meshes").glob(f"{CAR_NAME}*.glb"))
    if not hdrs or not cars:
        raise SystemExit(f"need hdri/{HDR_NAME}*.hdr and meshes/{CAR_NAME}*.glb under {args.shared}")
    envs = [("booth", "booth"), ("sky", "sky"), (hdrs[0].stem, str(hdrs[0]))]
    models = [("procedural car", "car"), (cars[0].stem + " (CC0)", str(cars[0]))]
    t_wall, t_cpu = time.perf_counter(), time.process_time()
    n = len(envs) * len(models) * len(PAINTS) + 2 * len(models) * 2 * 2 + 2 * len(envs) * len(PAINTS)
    progress = Progress(n, start=t_wall)
    OUT.mkdir(parents=True, exist_ok=True)
    figures = Figures()
    with tempfile.TemporaryDirectory(prefix="render-figures-") as tmp_name:
        tmp = Path(tmp_name)
        designs = _design_files(tmp, figures)
        _contact_sheet(progress, tmp, designs, envs, models, figures)
        _flake_sheet(progress, tmp, designs, models, figures)
        _error_maps(progress, tmp, designs, envs, figures)
    _write_doc_block(figures, envs[2][0], models[1][0])
    child = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = time.process_time() - t_cpu + child.ru_utime + child.ru_stime
    print(f"done: {time.perf_counter() - t_wall:.0f} s wall, {cpu:.0f} s CPU (this process and its renders)")


def _paint_label(code: str) -> str:
    return f"{code}\n{dict(PAINTS)[code]}"


def _contact_sheet(
    progress: Progress,
    tmp: Path,
    designs: dict[str, Path],
    envs: list[tuple[str, str]],
    models: list[tuple[str, str]],
    figures: Figures,
) -> None:
    rows: list[list[Path]] = []
    for env_name, env_arg in envs:
        row = []
        for model_name, mesh in models:
            for code, _ in PAINTS:
                out = tmp / f"sheet-{env_name}-{mesh.split('/')[-1]}-{code}.png"
                common = ["--design", str(designs[code]), "--env", env_arg, "--mesh", mesh, "--stage"]
                rep = _render(
                    progress,
                    f"sheet: {env_name}, {model_name}, {code}",
                    [*common, "--coat", COAT, "--flakes", "--size", str(TILE)],
                    out,
                )
                print(f"      flakes: {rep['flakes']}")
                figures.sheet_flakes[code] = str(rep["flakes"])
                row.append(out)
        rows.append(row)
    cols = [f"{m}: {_paint_label(c)}" for m, _ in models for c, _ in PAINTS]
    sheet = _labelled_grid(
        rows,
        cols,
        [e for e, _ in envs],
        "Three demo-library paints on two cars in three environments (stage, clear coat 1.5, flakes on)",
    )
    sheet.save(OUT / "paints-sheet.png")


def _flake_sheet(
    progress: Progress,
    tmp: Path,
    designs: dict[str, Path],
    models: list[tuple[str, str]],
    figures: Figures,
) -> None:
    """Sky, the red metallic and the blue pearl: flakes off | on, far (default view) and close."""
    shown = [PAINTS[1][0], PAINTS[2][0]]
    rows: list[list[Path]] = []
    labels: list[str] = []
    for model_name, mesh in models:
        for dist, view in (("far", None), ("close", CLOSE_VIEW)):
            row: list[Path] = []
            for code in shown:
                pair: dict[str, np.ndarray] = {}
                reason = ""
                for state in ("off", "on"):
                    out = tmp / f"flakes-{mesh.split('/')[-1]}-{dist}-{code}-{state}.png"
                    extra = (["--view", view] if view else []) + (["--flakes"] if state == "on" else [])
                    rep = _render(
                        progress,
                        f"flakes: {model_name}, {dist}, {code}, {state}",
                        ["--design", str(designs[code]), "--env", "sky", "--mesh", mesh, "--stage"]
                        + ["--coat", COAT, "--size", str(TILE), *extra],
                        out,
                        linear=True,
                    )
                    pair[state] = np.load(out.with_suffix(".npy"))
                    if state == "on":
                        reason = str(rep["flakes"])
                        print(f"      flakes: {reason}")
                    row.append(out)
                p95, count = _block_means_de(pair["off"], pair["on"], _white_sky())
                print(f"      {BLOCK}x{BLOCK} block means on vs off: p95 ΔE00 {p95:.2f} over {count} blocks")
                figures.flakes.append(
                    f"| {model_name} | {dist} | {code} ({dict(PAINTS)[code]}) | {reason} | {p95:.2f} ({count}) |"
                )
            rows.append(row)
            labels.append(f"{model_name}\n{dist}" + (f"\n--view {view}" if view else "\n(default view)"))
    cols = [f"{_paint_label(c)}, flakes {s}" for c in shown for s in ("off", "on")]
    _labelled_grid(
        rows, cols, labels, "Flakes off | on, far and close, sunny sky (stage, clear coat 1.5)"
    ).save(OUT / "paints-flakes.png")


_SKY_WHITE: list[float] = []


def _white_sky() -> float:
    if not _SKY_WHITE:
        _SKY_WHITE.append(_white("sky"))
    return _SKY_WHITE[0]


def _error_maps(
    progress: Progress,
    tmp: Path,
    designs: dict[str, Path],
    envs: list[tuple[str, str]],
    figures: Figures,
) -> None:
    """GL (one sample per pixel) against the truth engine on the sphere, ERROR_SIZE², no stage or coat."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from station.model.difference import delta_e
    from station.render import tonemap
    from station.render.numpy_renderer import gbuffer
    from station.render.shapes import Scene

    mask = gbuffer(Scene("sphere"), ERROR_SIZE, ERROR_SIZE).mask
    fig, axes = plt.subplots(
        len(envs), 3 * len(PAINTS), figsize=(2.0 * 3 * len(PAINTS), 2.35 * len(envs)), squeeze=False
    )
    image = None
    for r, (env_name, env_arg) in enumerate(envs):
        white = _white(env_arg)
        for c, (code, label) in enumerate(PAINTS):
            lin = {}
            for engine in ("gl", "truth"):
                out = tmp / f"err-{env_name}-{code}-{engine}.png"
                extra = ["--aa", "1"] if engine == "gl" else []
                _render(
                    progress,
                    f"error map: {env_name}, {code}, {engine}",
                    ["--design", str(designs[code]), "--env", env_arg, "--shape", "sphere"]
                    + ["--engine", engine, "--size", str(ERROR_SIZE), *extra],
                    out,
                    linear=True,
                )
                lin[engine] = np.load(out.with_suffix(".npy"))
            de = np.asarray(delta_e(_lab(lin["truth"], white), _lab(lin["gl"], white), "cie2000"))
            mean, p95, mx = float(de[mask].mean()), float(np.percentile(de[mask], 95)), float(de[mask].max())
            print(f"      ΔE00 GL vs truth, {env_name}, {code}: mean {mean:.2f}, p95 {p95:.2f}, max {mx:.1f}")
            figures.errors.append(f"| {env_name} | {code} ({label}) | {mean:.2f} | {p95:.2f} | {mx:.1f} |")
            shown = np.where(mask, de, np.nan)
            for k, (pic, name) in enumerate(
                (
                    (tonemap.to_display(lin["gl"]), "GL"),
                    (tonemap.to_display(lin["truth"]), "truth"),
                )
            ):
                ax = axes[r, 3 * c + k]
                ax.imshow(pic)
                ax.set_title(f"{code} {name}", fontsize=7)
            ax = axes[r, 3 * c + 2]
            image = ax.imshow(shown, cmap="magma", vmin=0.0, vmax=DE_MAX)
            ax.set_title(f"ΔE00 mean {mean:.2f} p95 {p95:.2f}", fontsize=7)
            axes[r, 0].set_ylabel(env_name, fontsize=9)
    for ax in axes.flat:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(
        "GL against the truth engine, sphere "
        f"{ERROR_SIZE}², no stage or coat: ΔE00 per pixel (colour bar clipped at {DE_MAX:g})",
        fontsize=10,
    )
    fig.tight_layout(rect=(0.0, 0.0, 0.93, 0.96))
    if image is not None:
        bar = fig.add_axes((0.94, 0.1, 0.012, 0.8))
        fig.colorbar(image, cax=bar, label="ΔE00")
    fig.savefig(OUT / "paints-error.png", dpi=110)
    plt.close(fig)


BEGIN = "<!-- scripts/render_figures.py: begin (generated, do not edit by hand) -->"
END = "<!-- scripts/render_figures.py: end -->"


def _write_doc_block(figures: Figures, hdr: str, car: str) -> None:
    """Replace the text between BEGIN and END in docs/render.md with the figures and their numbers."""
    doc = ROOT / "docs" / "render.md"
    text = doc.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        raise SystemExit(f"docs/render.md lacks the markers {BEGIN!r} … {END!r}")
    metallic, pearl = figures.sheet_flakes[PAINTS[1][0]], figures.sheet_flakes[PAINTS[2][0]]
    lines = [
        BEGIN,
        "",
        "| code | paint | library type | face L\\* / a\\* / b\\* | flop L\\* / a\\* / b\\* | travel | gloss "
        "| default flakes | fit residual, max ΔE00 |",
        "|---|---|---|---|---|---|---|---|---|",
        *figures.paints,
        "",
        "![Three paints on two cars in three environments](render/paints-sheet.png)",
        "",
        f"*Columns: the procedural car (`--mesh car`) and {car} (`--mesh FILE.glb`), each in the three "
        f"paints; rows: the booth, the sunny sky and {hdr} (CC0). `station render --stage --coat {COAT} "
        f"--flakes --size {TILE}`, default view, 4 samples per pixel. The flakes' level of detail in these "
        f'views: metallics "{metallic}", pearl "{pearl}".*',
        "",
        "![Flakes off | on, far and close](render/paints-flakes.png)",
        "",
        f"*Sunny sky, stage, coat {COAT}; far = the default mesh view, close = `--view {CLOSE_VIEW}`. "
        f"Block means: {BLOCK} × {BLOCK}-pixel means, flakes on against off, p95 ΔE00 over the blocks where "
        "at least half of the pixels changed (the painted blocks; their count in brackets).*",
        "",
        "| model | view | paint | flakes' level of detail (`--json`) | block means p95 ΔE00 (blocks) |",
        "|---|---|---|---|---|",
        *figures.flakes,
        "",
        "![GL against the truth engine, ΔE00 per pixel](render/paints-error.png)",
        "",
        f"*GL (`--engine gl --aa 1`) against the truth engine (`--engine truth`), sphere {ERROR_SIZE}², no "
        "stage, coat or flakes (the truth engine draws none of them), scene-linear outputs (`--linear-out`); "
        "CIE Lab relative to the brightest white-Lambertian pixel of the environment on a "
        f"{WHITE_SIZE}² sphere, ΔE00 over the sphere's pixels. Colour bar clipped at {DE_MAX:g}.*",
        "",
        "| environment | paint | mean ΔE00 | p95 | max |",
        "|---|---|---|---|---|",
        *figures.errors,
        "",
        END,
    ]
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    doc.write_text(head + "\n".join(lines) + tail, encoding="utf-8")


if __name__ == "__main__":
    main()
