"""USB and HID ids live in the family registry only: discovery asks for each family's ``usb_id``."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest

from station.drivers.discovery import list_devices
from station.drivers.families import FAMILIES, Family, family_named


def _family(name: str) -> Family:
    family = family_named(name)
    assert family is not None
    return family


def test_a_usb_or_hid_family_needs_ids_and_a_serial_family_has_none() -> None:
    with pytest.raises(ValueError, match="usb or hid transport has a"):
        Family("xyz", "m:C", "hid", "label")
    with pytest.raises(ValueError, match="usb or hid transport has a"):
        Family("xyz", "m:C", "serial", "label", usb_id=(0x1209, 1))
    with pytest.raises(ValueError, match="16-bit"):
        Family("xyz", "m:C", "usb", "label", usb_id=(0x1209, 0x10000))
    with pytest.raises(LookupError, match="serial line"):
        _family("ma6").device_id()


def test_hid_discovery_asks_for_each_hid_familys_ids() -> None:
    asked: list[tuple[int, int]] = []

    def enumerate_fn(vid: int, pid: int) -> list[dict[str, Any]]:
        asked.append((vid, pid))
        return [{"path": b"/dev/hidraw7", "manufacturer_string": "M", "product_string": "P"}]

    found, _ = list_devices(hid_enumerate=enumerate_fn)
    hid_families = [f for f in FAMILIES if f.transport == "hid"]
    assert asked == [f.device_id() for f in hid_families]
    assert {d.address for d in found if d.transport == "hid"} == {
        f"{f.name}@hid:/dev/hidraw7" for f in hid_families
    }


def test_usb_discovery_finds_the_simulated_ma3_by_the_familys_ids() -> None:
    from simulators.usb_backend import SimUsbBackend, SimUsbDevice

    ma3 = _family("ma3")
    vid, pid = ma3.device_id()
    right = SimUsbDevice(firmware=None)  # the simulator presents the family's ids by default
    wrong = replace(right, pid=(pid + 1) & 0xFFFF, address=8)
    found, notes = list_devices(usb_backend=SimUsbBackend([right, wrong]))
    usb = [d for d in found if d.transport == "usb"]
    assert [d.address for d in usb] == [f"ma3@usb:{vid:04x}:{pid:04x}"], notes


def test_the_simulators_present_the_registrys_ids() -> None:
    from simulators import gloss, usb_backend

    assert (gloss.VID, gloss.PID) == _family("gloss").device_id()
    assert usb_backend.MA3_USB_ID == _family("ma3").device_id()
