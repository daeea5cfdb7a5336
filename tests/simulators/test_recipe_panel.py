"""Recipe panels: a simulated panel painted with a `station formulate` recipe, measured through the real
driver stack (simulator subprocess on a pty, the runtime route), against the colorant model's own
prediction computed here directly (station.formulate.colorants.predict_lab / predict_gloss)."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from station.cli import main
from station.drivers import DriverInputError, GlossReading, open_instrument
from station.drivers.simproc import spawn_simulator
from station.errors import InputError
from station.formulate.batch import DEFAULT_BATCH_G
from station.formulate.colorants import default_database, predict_gloss, predict_lab
from station.formulate.effect_optics import GLOSS_CLEAR_GU, GLOSS_PER_MATTING
from station.model.difference import delta_e
from station.model.domain import DEFAULT_SCALE_RESOLUTION_G
from station.model.spectra import reflectance_to_lab

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

FAST = ["--measure-time", "0.02"]
READINGS = 10
# A red metallic with pearl and interference (angle-dependent) at 40 GU, as a recipe object
RED_METALLIC = {
    "white_tio2": 0.03,
    "black_carbon": 0.004,
    "orange_po": 0.19,
    "magenta_pv": 0.033,
    "alu_fine": 0.0087,
    "pearl_white": 0.066,
    "interference_blue": 0.08,
    "interference_gold": 0.09,
    "matting_silica": 50.0 / 650.0,
}


@pytest.fixture(scope="module")
def formulated(tmp_path_factory) -> tuple[dict, object]:
    """`station formulate "L,a,b;…" --gloss 40 --json` output written to a file: (parsed JSON, path)."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["formulate", "45,38,22;35,30,18;25,22,12", "--gloss", "40", "--json"])
    assert rc == 0
    data = json.loads(buf.getvalue())
    path = tmp_path_factory.mktemp("recipe") / "formulated.json"
    path.write_text(buf.getvalue())
    return data, path


def _predicted(recipe: dict[str, float], aspecular: tuple[int, ...]) -> np.ndarray:
    db = default_database()
    return predict_lab(db.vector(recipe), tuple(float(a) for a in aspecular), db)


def _round_trip(address: str) -> tuple[tuple[str, ...], tuple[int, ...], np.ndarray]:
    with open_instrument(address, timeout_s=1.0) as inst:
        readings = [inst.measure() for _ in range(READINGS)]
    lab = np.stack([reflectance_to_lab(r.reflectance) for r in readings])
    return readings[0].geometries, readings[0].aspecular_deg, lab


SILVER = {"alu_coarse": 0.1, "alu_fine": 0.05, "white_tio2": 0.02, "blue_pb": 0.005}


@pytest.mark.parametrize("panel", ["formulated", "silver"])
def test_ma6_recipe_round_trip(formulated, tmp_path, panel):
    """6 angles: mean ΔE00 over 10 readings to the formulate prediction within the repeatability
    (a dark red effect colour from `station formulate`, and a light silver given as a bare recipe object)."""
    data, path = formulated
    if panel == "silver":
        data, path = {"recipe": SILVER}, tmp_path / "silver.json"
        path.write_text(json.dumps(SILVER))
    with spawn_simulator("ma6", recipe_file=path, extra_args=FAST) as sim:
        geoms, aspec, lab = _round_trip(sim.address)
    assert geoms == ("45as-15", "45as15", "45as25", "45as45", "45as75", "45as110")
    de = delta_e(lab, _predicted(data["recipe"], aspec)[None], method="cie2000")  # (10, 6)
    assert float(de.mean()) <= 0.05, de.mean()
    assert float(de.max()) < 0.2
    # the noise-free mean reading sits on the prediction (no bias at --bias 0)
    bias = delta_e(lab.mean(0), _predicted(data["recipe"], aspec), method="cie2000")
    assert float(bias.max()) < 0.03


def test_ma3_matches_lab_printed_by_formulate(formulated):
    """MA3's 15/45/110° are formulate's own angles: compare with the predicted_lab it printed."""
    data, path = formulated
    assert data["angles_deg"] == [15.0, 45.0, 110.0]
    with spawn_simulator("ma3", recipe_file=path, extra_args=FAST) as sim:
        geoms, _, lab = _round_trip(sim.address)
    assert geoms == ("45as15", "45as45", "45as110")
    de = delta_e(lab, np.asarray(data["predicted_lab"])[None], method="cie2000")
    assert float(de.mean()) <= 0.05, de.mean()


def test_ma3_pyusb_route_and_panel_swap(formulated):
    """In process, the MA3 behind the pyusb backend (the USB driver's real code) reads the recipe panel;
    set_design puts a design panel back under it."""
    from simulators.ma3 import Ma3Firmware
    from simulators.physics import DEFAULT_DESIGN, InstrumentCharacter, SpectroPhysics
    from simulators.recipe import load_recipe
    from simulators.usb_backend import SimUsbBackend, SimUsbDevice
    from station.drivers.ma3 import MA3Spectro
    from station.drivers.transport import UsbTransport

    data, path = formulated
    physics = SpectroPhysics(character=InstrumentCharacter(serial="300456"), recipe=load_recipe(path))
    backend = SimUsbBackend([SimUsbDevice(Ma3Firmware(physics, measure_time_s=0.01))])
    inst = MA3Spectro(UsbTransport(0x1209, 0xCA03, "300456", backend=backend), timeout_s=0.5, retries=1)
    with inst.open():
        lab = np.stack([reflectance_to_lab(inst.measure().reflectance) for _ in range(READINGS)])
        physics.set_design(DEFAULT_DESIGN)
        back = reflectance_to_lab(inst.measure().reflectance)
    de = delta_e(lab, np.asarray(data["predicted_lab"])[None], method="cie2000")
    assert float(de.mean()) <= 0.05, de.mean()
    assert (
        float(delta_e(back, DEFAULT_DESIGN.lab_at(np.asarray([15.0, 45.0, 110.0])), method="cie2000").max())
        < 0.2
    )


def test_ma12_second_block_and_recipe_object(tmp_path):
    """The bare recipe object works too; the 15° illumination block is evaluated at its aspecular angles."""
    path = tmp_path / "red.json"
    path.write_text(json.dumps(RED_METALLIC))
    with spawn_simulator("ma6", recipe_file=path, extra_args=[*FAST, "--twelve"]) as sim:
        with open_instrument(sim.address, timeout_s=1.0) as inst:
            r = inst.measure()
    assert r.geometries[6:] == ("15as-45", "15as-15", "15as15", "15as25", "15as45", "15as60")
    de = delta_e(
        reflectance_to_lab(r.reflectance), _predicted(RED_METALLIC, r.aspecular_deg), method="cie2000"
    )
    assert de.shape == (12,) and float(de.max()) < 0.2
    # the flop really differs from the face (an effect recipe, not a flat panel)
    lab = reflectance_to_lab(r.reflectance)
    assert lab[1, 0] - lab[5, 0] > 10.0


def test_gloss_meter_reads_predicted_gloss(formulated):
    """The gloss simulator reads the 60° gloss the colorant model predicts from the matting fraction.

    ``--gloss 40`` sets the matting fraction in closed form (G = G_clear − g c, docs/formulate.md), then
    the recipe is weighed on the scale: the fraction lands within half a scale step (resolution / batch)
    of the closed form's, so the predicted gloss lies within g × step / 2 of 40 GU (0.0325 GU here)."""
    data, path = formulated
    db = default_database()
    step = DEFAULT_SCALE_RESOLUTION_G / DEFAULT_BATCH_G
    exact = (GLOSS_CLEAR_GU - 40.0) / GLOSS_PER_MATTING
    assert abs(data["recipe"]["matting_silica"] - exact) <= step / 2 + 1e-12
    expected = float(predict_gloss(db.vector(data["recipe"]), db))
    assert abs(expected - 40.0) <= GLOSS_PER_MATTING * step / 2 + 1e-9  # --gloss 40 reached the recipe
    with spawn_simulator("gloss", recipe_file=path, extra_args=FAST) as sim:
        with open_instrument(sim.address, timeout_s=1.0) as inst:
            g = [inst.measure() for _ in range(5)]
    assert all(isinstance(x, GlossReading) for x in g)
    assert abs(float(np.mean([x.gloss_gu[60] for x in g])) - expected) < 0.5  # the meter's ±0.5 GU class


def test_cli_measure_recipe_json(capsys, formulated):
    data, path = formulated
    rc = main(["measure", "sim:ma6", "--recipe", str(path), "--panel", "R-1", "--json"])
    out = capsys.readouterr()
    assert rc == 0, out.err
    got = json.loads(out.out)
    assert got["panel"] == "R-1" and np.asarray(got["spectra"]).shape == (6, 31)
    de = delta_e(
        np.asarray(got["lab"]), _predicted(data["recipe"], (-15, 15, 25, 45, 75, 110)), method="cie2000"
    )
    assert float(de.max()) < 0.2


@pytest.mark.parametrize(
    ("content", "field", "accepted"),
    [
        ('{"recipe": {"unobtainium": 0.1}}', "recipe.unobtainium", "a colorant of the database"),
        ('{"recipe": {"white_tio2": 0.9}}', "recipe.white_tio2", "0 <= fraction <= 0.45"),
        ('{"white_tio2": -0.01}', "recipe.white_tio2", "0 <= fraction <= 0.45"),
        ('{"recipe": {"white_tio2": "lots"}}', "recipe.white_tio2", "a finite mass fraction"),
        ('{"recipe": {}}', "recipe", "at least one colorant"),
        ('{"recipe": [0.1, 0.2]}', "recipe", "an object {colorant: mass fraction}"),
        ("[1, 2]", "recipe", "a JSON object"),
        ('{"white_tio2": 0.45, "yellow_py": 0.3}', "recipe", "total mass fraction <= 0.6"),
        (
            '{"alu_coarse": 0.2, "pearl_white": 0.1}',
            "recipe",
            "aluminium + pearl + interference fraction <= 0.25",
        ),
        ('{"recipe": ', "recipe_file", "JSON"),
    ],
)
def test_bad_recipe_file_is_a_typed_error(tmp_path, content, field, accepted):
    """The simulators' loader names the field and the accepted range (an InputError)."""
    from simulators.recipe import RecipeInputError, load_recipe

    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(RecipeInputError) as info:
        load_recipe(path)
    assert isinstance(info.value, InputError)
    assert info.value.field == field
    assert accepted in info.value.accepted


def test_refused_recipe_crosses_the_process_boundary_typed(tmp_path):
    """The simulator process refuses the file; spawn_simulator raises DriverInputError with its field."""
    path = tmp_path / "bad.json"
    path.write_text('{"recipe": {"interference_gold": 0.2}}')
    with pytest.raises(DriverInputError) as info:
        spawn_simulator("ma6", recipe_file=path)
    assert info.value.field == "recipe.interference_gold"
    assert info.value.accepted == "0 <= fraction <= 0.15" and info.value.got == 0.2


def test_bad_recipe_cli_exit_2(capsys, tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"recipe": {"black_carbon": 0.5}}')
    rc = main(["measure", "sim:ma3", "--recipe", str(path), "--json"])
    err = capsys.readouterr().err
    assert rc == 2 and "recipe.black_carbon" in err and "0 <= fraction <= 0.1" in err
    rc = main(["measure", "sim:ma6", "--recipe", str(path), "--design", str(path)])
    assert rc == 2 and "--recipe" in capsys.readouterr().err
    rc = main(["measure", "/dev/ttyACM0", "--recipe", str(path)])
    assert rc == 2 and "sim:" in capsys.readouterr().err


def test_missing_or_doubled_recipe_file(tmp_path):
    with pytest.raises(DriverInputError) as info:
        spawn_simulator("ma6", recipe_file=tmp_path / "missing.json")
    assert info.value.field == "recipe_file"
    path = tmp_path / "r.json"
    path.write_text(json.dumps(RED_METALLIC))
    with pytest.raises(DriverInputError) as info:
        spawn_simulator("ma6", design_file=path, recipe_file=path)
    assert info.value.field == "recipe_file"
