"""Regenerate the figures of docs/booth.md: ``python -m ui.booth_figures [--out docs/images]``.

The paints are a metameric pair made from the example silver metallic (``station.model.examples.SILVER``,
its Lab at 15°, 25°, 45°, 75°, 110° turned into smooth spectra by ``reflectance_from_lab``): the standard,
and a trial that adds a fifth of the largest admissible metameric black (``station.model.booth.metameric_pair``,
strength 0.2): equal under D65, about 10 ΔE00 apart at the face under A (12 under F11). Written:

* ``booth-car-d65.png``, ``booth-car-a.png``, ``booth-car-f11.png`` — the car (standard on the rear half,
  trial on the front) in the booth under each illuminant (:func:`station.render.booth.render_booth_png`);
* ``booth-tab.png`` — the viewer's Booth tab on the same pair, stored in a scratch database as two
  measurements of a job, under A on the car (Qt's offscreen platform; the screen has no GL widget).

Returns (and prints) the written paths.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import tempfile
import uuid
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from station.model.domain import ANGLES_5, DEFAULT_BOOTH_ILLUMINANTS

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

#: The pair's geometries (aspecular degrees) and metameric strength.
ANGLES = ANGLES_5
STRENGTH = 0.2
#: Picture side of the car figures and of the screen's picture (pixels).
FIGURE_SIZE = 384
#: The viewer window's size for the screenshot.
WINDOW = (1180, 560)


def silver_pair() -> tuple[np.ndarray, np.ndarray]:
    """(standard, trial) spectra (5, 31) of the metameric silver pair (module doc)."""
    from station.model.booth import metameric_pair
    from station.model.examples import SILVER
    from station.model.spectra import reflectance_from_lab

    std, smp = metameric_pair(reflectance_from_lab(SILVER.lab_at(ANGLES)), strength=STRENGTH)
    return std, smp


def car_figures(out: Path) -> list[Path]:
    """The car under D65, A and F11 (module doc)."""
    from station.model.examples import SILVER
    from station.render.booth import BoothPaint, BoothRenderer, render_booth_png

    std, smp = silver_pair()
    paints = (
        BoothPaint(ANGLES, std, SILVER.gloss_gu, "standard"),
        BoothPaint(ANGLES, smp, SILVER.gloss_gu, "trial"),
    )
    renderer = BoothRenderer(FIGURE_SIZE, isolate_gl=True)
    return [
        render_booth_png(
            *paints, ill, shape="car", out_path=out / f"booth-car-{ill.lower()}.png", renderer=renderer
        )
        for ill in DEFAULT_BOOTH_ILLUMINANTS
    ]


def add_pair(
    session: Session, pair: tuple[np.ndarray, np.ndarray], *, job: str, serial: str, operator: str
) -> list[int]:
    """Store *pair* (standard, trial spectra (5, 31), reflectance 0..1 at :data:`ANGLES`) in *session* as
    two measurements of *job* (fender standard, bumper trial: the job's panel of each part, made when it
    has none) by one spectrophotometer *serial*, taken a minute apart from 2026-12-01 09:00 UTC; Lab
    rounded to 4 decimals, spectra to 6. Stored through the one writer (:func:`station.ingest.store_reading`);
    returns their ids (flushed, not committed)."""
    from station.ingest import InstrumentRef, PanelRef, Reading, store_reading
    from station.model.spectra import WAVELENGTHS, reflectance_to_lab

    instrument = InstrumentRef(serial=serial, model="MA-T12", kind="spectrophotometer")
    ids = []
    for k, (part, sp) in enumerate(zip(("fender", "bumper"), pair, strict=True)):
        reading = Reading(
            client_id=uuid.uuid4(),
            instrument=instrument,
            panel=PanelRef(job=job, part=part),
            operator=operator,
            measured_at=dt.datetime(2026, 12, 1, 9, k, tzinfo=dt.UTC),
            geometries_deg=list(ANGLES),
            lab=reflectance_to_lab(sp).round(4).tolist(),
            wavelengths_nm=WAVELENGTHS.tolist(),
            spectra=sp.round(6).tolist(),
        )
        ids.append(store_reading(session, reading).measurement_id)
    return ids


def _scratch_database(folder: Path) -> tuple[str, list[int]]:
    """A database with the pair as two measurements of job J-BOOTH (fender standard, bumper trial)."""
    from db.engine import make_engine, make_sessionmaker
    from db.migrate import ensure_at_head

    url = f"sqlite:///{folder / 'booth.sqlite3'}"
    ensure_at_head(url)
    engine = make_engine(url)
    with make_sessionmaker(engine)() as session:
        ids = add_pair(session, silver_pair(), job="J-BOOTH", serial="T12-0001", operator="demo")
        session.commit()
    engine.dispose()
    return url, ids


def tab_screenshot(out: Path) -> Path:
    """The Booth tab on the pair under A on the car (module doc)."""
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide6.QtWidgets import QApplication

    from station.render.booth import BoothRenderer
    from ui.models.booth import BoothModel, LocalBoothSource
    from ui.widgets.booth_screen import BoothScreen

    app = QApplication.instance() or QApplication([])
    with tempfile.TemporaryDirectory(prefix="booth-figures-") as tmp:
        url, (std_id, smp_id) = _scratch_database(Path(tmp))
        screen = BoothScreen(BoothModel(LocalBoothSource(url), BoothRenderer(FIGURE_SIZE, isolate_gl=True)))
        screen.resize(*WINDOW)
        screen.show()
        for role, mid in (("standard", std_id), ("trial", smp_id)):
            screen.pickers[role].setCurrentIndex(screen.pickers[role].findData(mid))
            screen.pick_history(role)
        screen.shape.setCurrentText("car")
        screen.illuminant_btns["A"].click()
        app.processEvents()
        path = out / "booth-tab.png"
        screen.grab().save(str(path), "PNG")
        screen.close()
        screen.deleteLater()
        app.processEvents()
    return path


def write_figures(out: str | Path) -> list[Path]:
    """Write every figure of docs/booth.md to *out* (created if needed)."""
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    return [*car_figures(folder), tab_screenshot(folder)]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m ui.booth_figures", description=__doc__.split("\n")[0])
    ap.add_argument(
        "--out", type=Path, default=Path("docs/images"), help="output folder (default docs/images)"
    )
    args = ap.parse_args(argv)
    for path in write_figures(args.out):
        print(path)


if __name__ == "__main__":
    main()
