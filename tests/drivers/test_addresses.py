"""The instrument-address allow-list: supported transports pass, pyserial's other URL handlers and files do not."""

from __future__ import annotations

from pathlib import Path

import pytest

from station.drivers import DriverInputError
from station.drivers.addresses import check_address, parse_host_entry
from station.drivers.transport import SerialTransport

ACCEPTED = [
    "sim:ma6",
    "sim:gloss",
    "ma6@/dev/ttyUSB0",
    "ma6@/dev/ttyACM12",
    "ma3@/dev/ttyACM0",
    "ma6@/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A50285BI-if00-port0",
    "ma6@COM3",
    "ma3@usb:1209:ca03",
    "ma3@usb:1209:ca03:SN-0001",
    "gloss@hid:1209:ca60",
    "gloss@hid:/dev/hidraw2",
]
REFUSED = [
    "ma6@spy:///dev/null?file=/tmp/station.sqlite3",
    "ma6@loop://",
    "ma6@hwgrep://.*",
    "ma6@alt:///dev/ttyUSB0?class=PosixPollSerial",
    "ma6@/etc/passwd",
    "ma6@/dev/ttyUSB0/../../etc/passwd",
    "ma6@/dev/serial/by-id/../../sda",
    "ma6@/dev/sda",
    "ma6@/dev/pts/3",
    "ma6@socket://127.0.0.1:5432",
    "ma6@rfc2217://10.0.0.9:2217",
    "ma6@socket://127.0.0.1:4001?logging=debug",
    "ma6@usb:1209:ca03",  # USB bulk is the ma3 family's transport
    "gloss@hid:/etc/shadow",
    "ma9@/dev/ttyUSB0",
    "sim:ma9",
    "/dev/ttyUSB0\n",
    "ma6@/dev/ttyUSB0\n",
    "ma6@/dev/ttyUSB0\x00",
]


@pytest.mark.parametrize("address", ACCEPTED)
def test_supported_transports_pass(address: str) -> None:
    assert check_address(address) == address


@pytest.mark.parametrize("address", REFUSED)
def test_everything_else_is_refused_naming_the_field(address: str) -> None:
    with pytest.raises(DriverInputError) as err:
        check_address(address)
    assert err.value.field == "address"
    assert address not in str(err.value)  # the refusal says what is accepted, never echoes a path


def test_tcp_only_to_configured_hosts() -> None:
    hosts = ["10.0.0.9", "lab-bridge:4001"]
    assert check_address("ma6@rfc2217://10.0.0.9:2217", tcp_hosts=hosts)
    assert check_address("ma6@socket://LAB-BRIDGE:4001", tcp_hosts=hosts)
    for address in ("ma6@socket://lab-bridge:4002", "ma6@socket://10.0.0.10:2217"):
        with pytest.raises(DriverInputError):
            check_address(address, tcp_hosts=hosts)
    assert parse_host_entry(" [::1]:4001 ") == ("[::1]", 4001)
    with pytest.raises(DriverInputError):
        parse_host_entry("host:99999")


def test_serial_transport_never_hands_other_urls_to_pyserial(tmp_path: Path) -> None:
    target = tmp_path / "trace.log"
    for url in (f"spy:///dev/null?file={target}", "loop://", "hwgrep://.*"):
        with pytest.raises(DriverInputError):
            SerialTransport(url).open()
    assert not target.exists()
