"""A pyusb backend (``usb.backend.IBackend``) whose devices are simulated firmware objects.

``usb.core.find(backend=SimUsbBackend([...]))`` enumerates them and the driver's real pyusb code runs:
descriptors, ``set_configuration``, ``claim_interface``, bulk transfers on EP 0x01 OUT / 0x81 IN
(64-byte packets) and string descriptors over control transfers. Errors are raised the way the
libusb1 backend raises them (``USBError`` with errno; ``USBTimeoutError`` on timeout), so the driver's
error mapping is exercised: EBUSY when another handle holds the interface, ENODEV after an unplug.
"""

from __future__ import annotations

import array
import errno
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import usb.backend
import usb.core

from station.drivers.families import FAMILIES

__all__ = ["SimUsbBackend", "SimUsbDevice"]

PACKET = 64
#: The ids a simulated device presents by default: the ma3 family's (``station.drivers.families``).
MA3_USB_ID = next(f for f in FAMILIES if f.name == "ma3").device_id()


@dataclass(eq=False)
class SimUsbDevice:
    """One simulated USB device: ids, strings and the firmware behind its bulk endpoints."""

    firmware: Any
    vid: int = MA3_USB_ID[0]
    pid: int = MA3_USB_ID[1]
    manufacturer: str = "CACAD Sim"
    product: str = "MA3 simulated spectrophotometer"
    serial: str = "300456"
    bus: int = 1
    address: int = 7
    claimed_by: Any = None
    handles: list[Any] = field(default_factory=list)

    @property
    def unplugged(self) -> bool:
        """Whether the firmware has gone away."""
        return bool(getattr(self.firmware, "unplugged", False))


def _err(text: str, code: int, eno: int) -> usb.core.USBError:
    return usb.core.USBError(text, code, eno)


class SimUsbBackend(usb.backend.IBackend):
    """pyusb backend over :class:`SimUsbDevice` objects."""

    def __init__(self, devices: list[SimUsbDevice]) -> None:
        self.devices = devices

    def enumerate_devices(self):
        yield from (d for d in self.devices if not d.unplugged)

    def get_device_descriptor(self, dev: SimUsbDevice) -> SimpleNamespace:
        return SimpleNamespace(
            bLength=18,
            bDescriptorType=1,
            bcdUSB=0x0200,
            bDeviceClass=0xFF,
            bDeviceSubClass=0,
            bDeviceProtocol=0,
            bMaxPacketSize0=64,
            idVendor=dev.vid,
            idProduct=dev.pid,
            bcdDevice=0x0207,
            iManufacturer=1,
            iProduct=2,
            iSerialNumber=3,
            bNumConfigurations=1,
            address=dev.address,
            bus=dev.bus,
            port_number=1,
            port_numbers=(1,),
            speed=3,
        )

    def get_configuration_descriptor(self, dev: SimUsbDevice, config: int) -> SimpleNamespace:
        return SimpleNamespace(
            bLength=9,
            bDescriptorType=2,
            wTotalLength=32,
            bNumInterfaces=1,
            bConfigurationValue=1,
            iConfiguration=0,
            bmAttributes=0x80,
            bMaxPower=50,
            extra_descriptors=[],
        )

    def get_interface_descriptor(
        self, dev: SimUsbDevice, intf: int, alt: int, config: int
    ) -> SimpleNamespace:
        if intf != 0 or alt != 0:
            raise IndexError("no such interface")
        return SimpleNamespace(
            bLength=9,
            bDescriptorType=4,
            bInterfaceNumber=0,
            bAlternateSetting=0,
            bNumEndpoints=2,
            bInterfaceClass=0xFF,
            bInterfaceSubClass=0,
            bInterfaceProtocol=0,
            iInterface=0,
            extra_descriptors=[],
        )

    def get_endpoint_descriptor(
        self, dev: SimUsbDevice, ep: int, intf: int, alt: int, config: int
    ) -> SimpleNamespace:
        if ep > 1:
            raise IndexError("no such endpoint")
        return SimpleNamespace(
            bLength=7,
            bDescriptorType=5,
            bEndpointAddress=(0x01, 0x81)[ep],
            bmAttributes=0x02,
            wMaxPacketSize=PACKET,
            bInterval=0,
            bRefresh=0,
            bSynchAddress=0,
            extra_descriptors=[],
        )

    def open_device(self, dev: SimUsbDevice) -> SimpleNamespace:
        if dev.unplugged:
            raise _err("No such device (it may have been disconnected)", -4, errno.ENODEV)
        handle = SimpleNamespace(dev=dev)
        dev.handles.append(handle)
        return handle

    def close_device(self, dev_handle: SimpleNamespace) -> None:
        dev = dev_handle.dev
        if dev.claimed_by is dev_handle:
            dev.claimed_by = None
        if dev_handle in dev.handles:
            dev.handles.remove(dev_handle)
        dev.firmware.on_hangup()

    def set_configuration(self, dev_handle: SimpleNamespace, config_value: int) -> None:
        self._alive(dev_handle)

    def get_configuration(self, dev_handle: SimpleNamespace) -> int:
        return 1

    def set_interface_altsetting(self, dev_handle: SimpleNamespace, intf: int, altsetting: int) -> None:
        self._alive(dev_handle)

    def claim_interface(self, dev_handle: SimpleNamespace, intf: int) -> None:
        dev = self._alive(dev_handle)
        if dev.claimed_by is not None and dev.claimed_by is not dev_handle:
            raise _err("Resource busy", -6, errno.EBUSY)
        dev.claimed_by = dev_handle

    def release_interface(self, dev_handle: SimpleNamespace, intf: int) -> None:
        if dev_handle.dev.claimed_by is dev_handle:
            dev_handle.dev.claimed_by = None

    def _alive(self, dev_handle: SimpleNamespace) -> SimUsbDevice:
        dev = dev_handle.dev
        if dev.unplugged:
            raise _err("No such device (it may have been disconnected)", -4, errno.ENODEV)
        return dev

    def bulk_write(self, dev_handle: SimpleNamespace, ep: int, intf: int, data: Any, timeout: int) -> int:
        dev = self._alive(dev_handle)
        if dev.claimed_by is not dev_handle:
            raise _err("Resource busy", -6, errno.EBUSY)
        dev.firmware.receive(bytes(data))
        return len(data)

    def bulk_read(
        self, dev_handle: SimpleNamespace, ep: int, intf: int, buff: array.array, timeout: int
    ) -> int:
        dev = self._alive(dev_handle)
        fw = dev.firmware
        if not fw.wait_ready(timeout / 1000.0):
            self._alive(dev_handle)
            raise usb.core.USBTimeoutError("Operation timed out", -7, errno.ETIMEDOUT)
        self._alive(dev_handle)
        data = fw.pop_ready(min(len(buff), PACKET))
        buff[: len(data)] = array.array("B", data)
        return len(data)

    def ctrl_transfer(
        self,
        dev_handle: SimpleNamespace,
        bmRequestType: int,
        bRequest: int,
        wValue: int,
        wIndex: int,
        data_or_wLength: Any,
        timeout: int,
    ) -> int:
        dev = self._alive(dev_handle)
        if bmRequestType == 0x80 and bRequest == 0x06 and wValue >> 8 == 3:  # GET_DESCRIPTOR string
            index = wValue & 0xFF
            if index == 0:
                raw = bytes([4, 3, 0x09, 0x04])  # langid en-US
            else:
                text = {1: dev.manufacturer, 2: dev.product, 3: dev.serial}.get(index, "")
                enc = text.encode("utf-16-le")
                raw = bytes([2 + len(enc), 3]) + enc
            n = min(len(raw), len(data_or_wLength))
            data_or_wLength[:n] = array.array("B", raw[:n])
            return n
        raise _err("Pipe error (request not supported)", -9, errno.EPIPE)

    def clear_halt(self, dev_handle: SimpleNamespace, ep: int) -> None:
        self._alive(dev_handle)

    def reset_device(self, dev_handle: SimpleNamespace) -> None:
        self._alive(dev_handle).firmware.on_hangup()

    def is_kernel_driver_active(self, dev_handle: SimpleNamespace, intf: int) -> bool:
        return False

    def detach_kernel_driver(self, dev_handle: SimpleNamespace, intf: int) -> None:
        return None

    def attach_kernel_driver(self, dev_handle: SimpleNamespace, intf: int) -> None:
        return None
