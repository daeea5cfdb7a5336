"""Instrument is generic over its transport type: each family names the transport it speaks over,
the type checker sees ``transport`` as that type, and construction refuses another kind."""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest

from station.drivers import DriverInputError, make_instrument
from station.drivers.gloss import GlossMeter
from station.drivers.instrument import Instrument
from station.drivers.ma3 import MA3Spectro
from station.drivers.ma6 import MA6Spectro
from station.drivers.transport import (
    HidTransport,
    ReportTransport,
    SerialTransport,
    StreamTransport,
    UsbTransport,
)
from tests.processes import run


def test_each_family_declares_its_transport() -> None:
    assert MA6Spectro.transport_type is StreamTransport
    assert MA3Spectro.transport_type is StreamTransport
    assert GlossMeter.transport_type is ReportTransport
    assert issubclass(SerialTransport, StreamTransport) and issubclass(UsbTransport, StreamTransport)
    assert issubclass(HidTransport, ReportTransport)


def test_address_builds_the_family_on_its_transport() -> None:
    assert isinstance(make_instrument("ma6@/dev/ttyACM0").transport, SerialTransport)
    assert isinstance(make_instrument("ma3@usb:1209:ca03").transport, UsbTransport)
    assert isinstance(make_instrument("gloss@/dev/ttyUSB0").transport, HidTransport)


@pytest.mark.parametrize(
    ("family", "transport", "accepted"),
    [
        (GlossMeter, SerialTransport("/dev/ttyACM0"), "a ReportTransport for gloss"),
        (MA6Spectro, HidTransport(b"/dev/hidraw0"), "a StreamTransport for ma6"),
        (MA3Spectro, HidTransport(b"/dev/hidraw0"), "a StreamTransport for ma3"),
    ],
)
def test_wrong_kind_of_transport_is_refused(family: type, transport: object, accepted: str) -> None:
    with pytest.raises(DriverInputError) as info:
        family(transport)
    assert (info.value.field, info.value.accepted) == ("transport", accepted)
    assert info.value.got == type(transport).__name__


def test_subclass_of_a_family_keeps_its_transport_type() -> None:
    class Ma6Variant(MA6Spectro):
        family = "ma6v"

    assert Ma6Variant.transport_type is StreamTransport
    assert Instrument.transport_type.__name__ == "Transport"


def test_type_checker_sees_the_transport_type(tmp_path: Path) -> None:
    """mypy infers ``GlossMeter(...).transport`` as ReportTransport and ``MA6Spectro(...).transport`` as
    StreamTransport, and rejects a serial transport for the gloss meter."""
    import mypy  # noqa: F401  (a dev dependency: missing, the test fails)

    probe = tmp_path / "probe.py"
    probe.write_text(
        textwrap.dedent(
            """
            from station.drivers.gloss import GlossMeter
            from station.drivers.ma6 import MA6Spectro
            from station.drivers.transport import HidTransport, SerialTransport

            reveal_type(GlossMeter(HidTransport(b"x")).transport)
            reveal_type(MA6Spectro(SerialTransport("x")).transport)
            GlossMeter(SerialTransport("x"))
            """
        )
    )
    root = Path(__file__).resolve().parents[2]
    argv = [sys.executable, "-m", "mypy", "--ignore-missing-imports", "--follow-imports=silent", str(probe)]
    out = run(argv, cwd=root, timeout=300).stdout
    assert 'Revealed type is "station.drivers.transport.ReportTransport"' in out, out
    assert 'Revealed type is "station.drivers.transport.StreamTransport"' in out, out
    assert 'incompatible type "SerialTransport"; expected "ReportTransport"' in out, out
