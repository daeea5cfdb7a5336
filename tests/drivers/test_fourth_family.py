"""A fourth simulated instrument family is one entry in ``station/drivers/families.py``.

A copy of the product is made in a temporary folder and only its family registry is edited: a family
``ma6b`` reusing the 6-angle ASCII protocol (driver ``MA6Spectro``, simulator ``simulators.ma6``) is added
to :data:`~station.drivers.families.FAMILIES`. The test checks that nothing else in the copy differs from
the repository, then, run from that copy as a user runs it,

* ``station measure sim:ma6b --json`` spawns the simulator for the new family, measures through it and
  reports six geometries whose Lab (computed here with colour-science from the printed spectra) is that
  of the simulator's default panel measured as ``sim:ma6``, noise apart;
* ``station serve --simulators`` offers it (its refusal of an unknown kind lists ``ma6b``) and takes it;
* the viewer's device picker (the real ``InstrumentsScreen`` combo box, offscreen) lists ``sim:ma6b``;
* ``station instruments list --json`` shows it with its label, and the address allow-list accepts
  ``sim:ma6b`` and ``ma6b@/dev/ttyUSB0``.
"""

from __future__ import annotations

import filecmp
import json
import os
import shutil
import sys
from pathlib import Path

import colour
import numpy as np
import pytest

from tests.processes import run

REPO = Path(__file__).resolve().parents[2]
PACKAGES = ("station", "simulators", "ui", "db")
REGISTRY = Path("station/drivers/families.py")
NEW_FAMILY = """    Family(
        "ma6b",
        "station.drivers.ma6:MA6Spectro",
        "serial",
        "simulated 6-angle spectro, second family (ASCII serial)",
        simulator="simulators.ma6",
    ),
"""


def _copy_with_a_fourth_family(dest: Path) -> Path:
    """A copy of the packages with NEW_FAMILY appended to FAMILIES; returns the copy's root."""
    for pkg in PACKAGES:
        shutil.copytree(REPO / pkg, dest / pkg, ignore=shutil.ignore_patterns("__pycache__"))
    registry = dest / REGISTRY
    text = registry.read_text()
    head, sep, tail = text.partition("FAMILIES: tuple[Family, ...] = (\n")
    assert sep, "FAMILIES not found"
    body, closing, rest = tail.partition("\n)\n")
    assert closing, "the end of FAMILIES not found"
    registry.write_text(head + sep + body + "\n" + NEW_FAMILY + ")\n" + rest)
    return dest


def _differing(a: Path, b: Path, rel: Path = Path()) -> list[str]:
    cmp = filecmp.dircmp(a, b, ignore=["__pycache__"])
    out = [str(rel / n) for n in cmp.left_only + cmp.right_only + cmp.diff_files]
    for name in cmp.common_dirs:
        out += _differing(a / name, b / name, rel / name)
    return out


def _python(tree: Path, cwd: Path, *argv: str, timeout: float = 120) -> tuple[int, str, str]:
    env = dict(
        os.environ, PYTHONPATH=str(tree), STATION_CACHE_DIR=str(cwd / "cache"), QT_QPA_PLATFORM="offscreen"
    )
    env.pop("CACAD_DATABASE_URL", None)
    res = run([sys.executable, *argv], cwd=cwd, env=env, timeout=timeout)
    return res.returncode, res.stdout, res.stderr


@pytest.fixture(scope="module")
def tree(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _copy_with_a_fourth_family(tmp_path_factory.mktemp("product"))


@pytest.fixture
def user(tmp_path: Path) -> Path:
    folder = tmp_path / "user"
    folder.mkdir()
    return folder


def test_only_the_registry_differs(tree: Path) -> None:
    changed = [c for pkg in PACKAGES for c in _differing(REPO / pkg, tree / pkg, Path(pkg))]
    assert changed == [str(REGISTRY)]


def test_station_measure_measures_the_new_family(tree: Path, user: Path) -> None:
    rc, out, err = _python(tree, user, "-m", "station.cli", "measure", "sim:ma6b", "--json")
    assert rc == 0, err
    new = json.loads(out)
    rc, out, err = _python(tree, user, "-m", "station.cli", "measure", "sim:ma6", "--json")
    assert rc == 0, err
    old = json.loads(out)
    assert (
        new["geometries"]
        == old["geometries"]
        == ["45as-15", "45as15", "45as25", "45as45", "45as75", "45as110"]
    )
    # Lab from the printed spectra, computed independently (colour-science, D65, 10° observer)
    shape = colour.SpectralShape(400, 700, 10)
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"].copy().align(shape)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    white = colour.CCS_ILLUMINANTS["CIE 1964 10 Degree Standard Observer"]["D65"]

    def lab(spectra: list[list[float]]) -> np.ndarray:
        xyz = [
            colour.sd_to_XYZ(
                colour.SpectralDistribution(dict(zip(range(400, 701, 10), s, strict=True))),
                cmfs,
                d65,
                method="ASTM E308",
            )
            for s in spectra
        ]
        return np.array([colour.XYZ_to_Lab(np.asarray(x) / 100.0, white) for x in xyz])

    np.testing.assert_allclose(lab(new["spectra"]), lab(old["spectra"]), atol=1.5)  # same panel, noise apart


_SERVE = """
from station.cli.serve import _parse_sims
from station.errors import InputError
print(",".join(_parse_sims(None)))
print(",".join(_parse_sims("ma6b")))
try:
    _parse_sims("nope")
except InputError as exc:
    print(exc.accepted)
"""


def test_station_serve_offers_the_new_family(tree: Path, user: Path) -> None:
    rc, out, err = _python(tree, user, "-c", _SERVE)
    assert rc == 0, err
    default, chosen, accepted = out.splitlines()
    assert default == "ma6,ma3,gloss,ma6b"
    assert chosen == "ma6b"
    assert "ma6b" in accepted.split(" ")[-3].split(",")
    # the command itself: an unknown kind is refused (exit 2, one line) naming the new family among the
    # accepted ones, before the service starts
    rc, out, err = _python(tree, user, "-m", "station.cli", "serve", "--simulators", "ma6b,nope", timeout=60)
    assert rc == 2, err
    assert "--simulators" in err and "ma6,ma3,gloss,ma6b" in err


_PICKER = """
from PySide6.QtWidgets import QApplication
app = QApplication([])
from ui.models.instruments import MeasurementStore
from ui.models.measure_db import LocalSink
from ui.widgets.instruments_screen import InstrumentsScreen
screen = InstrumentsScreen(MeasurementStore(LocalSink("sqlite:///s.sqlite3", "outbox")))
print("\\n".join(screen.device.itemText(i) for i in range(screen.device.count())))
"""


def test_the_viewers_device_picker_offers_the_new_family(tree: Path, user: Path) -> None:
    rc, out, err = _python(tree, user, "-c", _PICKER)
    assert rc == 0, err
    assert out.split() == ["sim:ma6", "sim:ma3", "sim:gloss", "sim:ma6b"]


_ADDRESSES = """
from station.drivers.addresses import check_address
from station.drivers.discovery import list_devices
print(check_address("sim:ma6b"), check_address("ma6b@/dev/ttyUSB0"))
print([c.description for c in list_devices()[0] if c.address == "sim:ma6b"])
"""


def test_discovery_and_the_allow_list_take_the_new_family(tree: Path, user: Path) -> None:
    rc, out, err = _python(tree, user, "-c", _ADDRESSES)
    assert rc == 0, err
    first, second = out.splitlines()
    assert first == "sim:ma6b ma6b@/dev/ttyUSB0"
    assert second == "['simulated 6-angle spectro, second family (ASCII serial)']"
