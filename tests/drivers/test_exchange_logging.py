"""Drivers tell what they exchange: every command and reply is logged at debug level as hex and decoded
text (on the family's logger, and the raw bytes on ``station.drivers.wire``); their errors are also the
standard library's ``ConnectionError`` / ``TimeoutError``."""

from __future__ import annotations

import logging

import pytest

from station.drivers import CommunicationError, DeviceInUse, DeviceTimeout, Disconnected
from station.drivers.exchange_log import KEPT, ExchangeLog, hex_ascii
from station.drivers.ma6 import MA6Spectro
from station.drivers.transport import SerialTransport
from tests.drivers.conftest import scripted_pty

OK = b"<000>\r\n>"
ID_REPLY = b"MODEL=MA6\r\nSERIAL=600123\r\nFW=1.4.2\r\nGEOM=45as15,45as45\r\n" + OK


def test_hex_ascii_by_hand() -> None:
    assert hex_ascii(b"ID\r") == "49 44 0d |ID.|"
    assert hex_ascii(bytes(range(200)), limit=2) == "00 01 |..| …(200 bytes)"


def test_every_exchange_is_logged_as_hex_and_decoded(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger="station.drivers")
    pairs = [(b"\r", OK), (b"ID\r", ID_REPLY)]
    with (
        scripted_pty(pairs) as (path, _),
        MA6Spectro(SerialTransport(path), timeout_s=0.25, retries=1).open() as inst,
    ):
        assert inst.info is not None and inst.info.serial == "600123"
        assert [sent for sent, _ in inst.protocol.log] == [b"ID\r"]
    family = [r.getMessage() for r in caplog.records if r.name == "station.drivers.ma6"]
    assert len(family) == 1
    assert f"sent {b'ID'.hex(' ')} 0d |ID.|" in family[0]  # hex then ASCII of the command
    assert "4d 4f 44 45 4c 3d" in family[0] and "|MODEL=MA6" in family[0]  # the reply, hex and ASCII
    assert "'ID' -> code 0" in family[0]  # decoded: the command and the reply's status code
    wire = [r.getMessage() for r in caplog.records if r.name == "station.drivers.wire"]
    tx = [m for m in wire if " tx " in m]
    assert tx[-1].endswith("49 44 0d |ID.|") and path in tx[-1]
    received = b"".join(bytes.fromhex(m.split(" rx ")[1].split(" |")[0]) for m in wire if " rx " in m)
    assert received == OK + ID_REPLY  # the wire log holds every byte read, in order


def test_nothing_is_formatted_unless_debug_is_on(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="station.drivers")
    log = ExchangeLog("ma6", "/dev/pts/x")
    for k in range(KEPT + 5):
        log.record(bytes([k]), b"r", "decoded")
    assert not caplog.records
    assert len(log) == KEPT and log[0] == (bytes([5]), b"r")  # the oldest go first


@pytest.mark.parametrize(
    ("error", "standard"),
    [
        (CommunicationError("x"), ConnectionError),
        (Disconnected("x"), ConnectionError),
        (DeviceInUse("x"), ConnectionError),
        (DeviceTimeout("x", 7), TimeoutError),
    ],
)
def test_driver_errors_are_standard_errors_too(error: Exception, standard: type[Exception]) -> None:
    with pytest.raises(standard) as caught:
        raise error
    assert str(caught.value) == str(error)
