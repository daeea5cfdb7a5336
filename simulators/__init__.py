"""Device simulators: same wire protocols as the drivers expect, with the physics of the instruments.

Never imported by runtime code (``station``, ``db``; import-linter contract): the runtime starts them
as programs (``python -m simulators.ma6|ma3|gloss``, see ``station.drivers.simproc``). Tests import
them directly.

* :mod:`simulators.physics` — virtual panel, noise, bias, warm-up, calibration state
* :mod:`simulators.faults` — injectable faults (docs/protocols/faults.md)
* :mod:`simulators.pty_host` — serves a byte-stream device on a real pty; :mod:`simulators.rfc2217_server`
  puts it behind RFC 2217 or raw TCP
* :mod:`simulators.ma6` — 6/12-angle ASCII prompt protocol; :mod:`simulators.ma3` — binary frames,
  :mod:`simulators.usb_backend` — pyusb backend; :mod:`simulators.gloss` — HID gloss meter at the hidapi
  call boundary and its pty bridge
* :mod:`simulators.scripted` — exact (sent, reply) replay for byte-exact protocol tests
"""
