"""Simulators as subprocesses (the runtime route: station never imports simulators) and the
network forms of the serial transport (rfc2217:// with baud control, socket://)."""

from __future__ import annotations

import pytest

from station.drivers import DriverInputError, HardwareFailure, open_instrument
from station.drivers.simproc import spawn_simulator
from station.model import FaceFlopTravelGloss
from station.model.angles import flake_equivalent_aspecular
from station.model.difference import delta_e
from station.model.spectra import reflectance_to_lab

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


@pytest.mark.parametrize("scheme", ["rfc2217", "socket"])
def test_ma6_behind_network_server(scheme):
    """rfc2217:// (baud negotiation passes through the server to the pty) and raw socket://."""
    from simulators.ma6 import Ma6Device
    from simulators.physics import SpectroPhysics
    from simulators.pty_host import PtyHost
    from simulators.rfc2217_server import Rfc2217Server

    design = FaceFlopTravelGloss(
        face=(45.0, 38.0, 22.0), flop=(25.0, 30.0, 12.0), travel_deg=70.0, gloss_gu=85.0
    )
    dev = Ma6Device(SpectroPhysics(design=design), measure_time_s=0.01)
    with PtyHost(dev) as host:
        srv = Rfc2217Server(host.path, raw=scheme == "socket").start()
        try:
            assert srv.url.startswith(f"{scheme}://")
            with open_instrument(f"ma6@{srv.url}", timeout_s=1.0) as inst:
                r = inst.measure()
        finally:
            srv.close()
    assert dev.baud == (115200 if scheme == "rfc2217" else 9600)  # socket:// has no baud rate
    lab = reflectance_to_lab(r.reflectance)
    de = delta_e(lab, design.lab_at(flake_equivalent_aspecular(r.aspecular_deg)), method="cie2000")
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

    with spawn_simulator("ma3", faults=["lamp-failure@MS:1"], extra_args=["--measure-time", "0.02"]) as sim:
        assert sim.address.startswith("ma3@/dev/")
        with open_instrument(sim.address, timeout_s=1.0) as inst:
            with pytest.raises(HardwareFailure):  # the --fault flag reached the simulator
                inst.measure()
            r = inst.measure()
            assert r.geometries == ("45as15", "45as45", "45as110")
            assert inst.calibrate().passed
    with spawn_simulator("gloss", extra_args=["--measure-time", "0.02"]) as sim:
        assert sim.address.startswith("gloss@/dev/")
        with open_instrument(sim.address, timeout_s=1.0) as inst:
            g = inst.measure()
    assert isinstance(g, GlossReading)
    assert abs(g.gloss_gu[60] - 88.0) < 0.6
