"""Simulators as subprocesses (the runtime route: station never imports simulators) and the
network forms of the serial transport (rfc2217:// with baud control, socket://)."""

from __future__ import annotations

import numpy as np
import pytest

from station.drivers import DriverInputError, HardwareFailure, SpectralReading, open_instrument
from station.drivers.simproc import spawn_simulator
from station.model import FaceFlopTravelGloss
from station.model.design_io import save_design
from station.model.difference import delta_e
from station.model.spectra import reflectance_to_lab

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


@pytest.mark.parametrize("net", ["--rfc2217", "--tcp"])  # the plain pty route: tests/drivers/test_cli.py
def test_ma6_subprocess_measures_design(tmp_path, net):
    design = FaceFlopTravelGloss(face=(45.0, 38.0, 22.0), flop=(25.0, 30.0, 12.0), travel_deg=70.0, gloss_gu=85.0)
    path = save_design(design, tmp_path / "red.json")
    extra = ["--measure-time", "0.02", net]
    faults = ["lamp-failure@MS:1"] if net == "--tcp" else []  # the --fault flag reaches the simulator
    with spawn_simulator("ma6", design_file=path, faults=faults, extra_args=extra) as sim:
        assert sim.kind == "ma6"
        scheme = {"--rfc2217": "ma6@rfc2217://", "--tcp": "ma6@socket://"}[net]
        assert sim.address.startswith(scheme)
        with open_instrument(sim.address, timeout_s=1.0) as inst:
            if faults:
                with pytest.raises(HardwareFailure):
                    inst.measure()
            r = inst.measure()
    assert isinstance(r, SpectralReading)
    lab = reflectance_to_lab(r.reflectance)
    de = delta_e(lab, design.lab_at(np.asarray(r.aspecular_deg)), method="cie2000")
    assert float(de.max()) < 0.15


def test_unknown_kind_and_missing_design(tmp_path):
    with pytest.raises(DriverInputError):
        spawn_simulator("ma9")
    with pytest.raises(DriverInputError):
        spawn_simulator("ma6", design_file=tmp_path / "missing.json")


def test_bad_fault_flag_fails_fast():
    from station.drivers import CommunicationError

    with pytest.raises(CommunicationError, match="unknown fault"):
        spawn_simulator("ma6", faults=["no-such-fault"])


def test_ma3_and_gloss_subprocess_routes():
    """sim:ma3 serves the binary frames on a pty; sim:gloss bridges hidapi calls over a pty."""
    from station.drivers import GlossReading

    with spawn_simulator("ma3", extra_args=["--measure-time", "0.02"]) as sim:
        assert sim.address.startswith("ma3@/dev/")
        with open_instrument(sim.address, timeout_s=1.0) as inst:
            r = inst.measure()
            assert r.geometries == ("45as15", "45as45", "45as110")
            assert inst.calibrate().passed
    with spawn_simulator("gloss", extra_args=["--measure-time", "0.02"]) as sim:
        assert sim.address.startswith("gloss@/dev/")
        with open_instrument(sim.address, timeout_s=1.0) as inst:
            g = inst.measure()
    assert isinstance(g, GlossReading)
    assert abs(g.gloss_gu[60] - 88.0) < 0.6
