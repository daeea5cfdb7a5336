"""``station instruments list``, ``station calibrate DEVICE``, ``station measure DEVICE``.

DEVICE is ``sim:ma6`` / ``sim:ma3`` / ``sim:gloss`` (a simulator subprocess started for the command;
``--design FILE`` or ``--recipe FILE`` — ``station formulate --json`` output — sets its panel) or an address accepted by :func:`station.drivers.open_instrument`
(``/dev/ttyACM0``, ``ma3@usb:1209:ca03``, ``gloss@hid:PATH`` …). Lab comes from
``station.model.spectra.reflectance_to_lab`` (D65, CIE 1964 10°), never from the driver.

``station calibrate DEVICE`` calibrates step by step (``station.scan.CalibrationSession``): before each
step (black trap, white tile, verification tile; a gloss meter's standard) its prompt goes to stderr and
Enter runs it, ``q`` or end of input cancels (one line, exit 1, not calibrated); ``--yes`` runs them all
without asking. ``station measure DEVICE --calibrate`` does the same for DEVICE and its ``--gloss`` meter
before measuring.

Every measurement goes through ``station.scan``, the scan path the viewer and the service use too.
``station measure DEVICE --gloss GLOSS_DEVICE`` reads the gloss meter first (``station.scan.take``): its
60° gloss goes into the colour record. ``--store [URL]`` also stores the reading (``station.scan.store``):
through ``station.ingest.Ingestor`` (exactly once by client id; queued in ``--outbox`` when the database
is away and sent by the next ``--store``) into URL, or by default the database ``station serve`` uses
(``$CACAD_DATABASE_URL``, else ``station.sqlite3`` in ``$CACAD_DATA_DIR`` or ``./var``), upgraded to the
current schema on first use; the paired meter's whole reading then becomes a gloss reading naming the
measurement. A gloss meter alone gives a gloss-only reading (20/60/85 GU, haze, DOI, Rspec), stored as a
gloss reading of its own on the ``--panel`` given, directly (not queued): the QC views pair it with a
colour reading of the same panel.

``station measure DEVICE --out FILE [--out FILE …] [--format cxf|cgats|csv|xlsx] [--sample NAME]`` also
writes the reading (every geometry, spectra and Lab) as a CxF3, CGATS.17, MA-T12 workbook or CSV file that
``station import`` reads (docs/import.md): how the simulators write each vendor format.
"""

from __future__ import annotations

import argparse
import sys
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from station.cli._common import Steps, add_json_flag
from station.errors import InputError


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``instruments``, ``calibrate`` and ``measure``."""
    p = subparsers.add_parser("instruments", help="list instruments")
    sub = p.add_subparsers(dest="instruments_command", required=True, metavar="ACTION")
    lp = sub.add_parser("list", help="serial ports, USB and HID candidates, simulators")
    add_json_flag(lp)
    lp.set_defaults(handler=cmd_list)

    for name, fn, text in (
        ("calibrate", cmd_calibrate, "black trap, white tile and verification tile, step by step"),
        ("measure", cmd_measure, "measure once and print spectra, Lab and gloss"),
    ):
        cp = subparsers.add_parser(name, help=text)
        cp.add_argument(
            "device",
            help="sim:FAMILY (the simulators of `station instruments list`) | an address (see docs/protocols)",
        )
        cp.add_argument("--design", type=Path, help="design file of the simulated panel (sim:* only)")
        cp.add_argument(
            "--recipe",
            type=Path,
            help="recipe file of the simulated panel: `station formulate --json` output (sim:* only)",
        )
        cp.add_argument("--fault", action="append", default=[], help="simulator fault spec (sim:* only)")
        cp.add_argument("--timeout", type=float, default=1.5, help="reply timeout, seconds")
        cp.add_argument(
            "--twelve",
            action="store_true",
            help="sim:ma6 only: 12 geometries in two illumination blocks (15° and 45°), as an MA-T12",
        )
        cp.add_argument(
            "--yes",
            action="store_true",
            help="run every calibration step without asking for its reference (black trap, white tile…)",
        )
        if name == "measure":
            _add_measure_options(cp)
        add_json_flag(cp)
        cp.set_defaults(handler=fn)


def _add_measure_options(cp: argparse.ArgumentParser) -> None:
    """Options of ``station measure`` beyond the device ones: gloss pairing, storage, files."""
    cp.add_argument(
        "--calibrate",
        action="store_true",
        help="calibrate first, step by step (and the --gloss meter on its standard)",
    )
    cp.add_argument(
        "--gloss",
        metavar="DEVICE",
        help="gloss meter read first (sim:gloss or an address): its 60° gloss is stored with the "
        "colour, its whole reading as a gloss reading of the measurement",
    )
    cp.add_argument("--panel", help="panel recorded with the reading (with --store: a panel id)")
    cp.add_argument(
        "--store",
        nargs="?",
        const="",
        metavar="URL",
        help="store the reading in database URL (default: the `station serve` database)",
    )
    cp.add_argument(
        "--outbox", type=Path, help="outbox file (default: measure-outbox.sqlite3 in the data folder)"
    )
    cp.add_argument(
        "--client-id",
        type=uuid.UUID,
        help="client id of the reading (a retry under it stores nothing new)",
    )
    cp.add_argument(
        "--illumination", type=int, default=45, help="illumination angle of the stored block, degrees"
    )
    cp.add_argument(
        "--out",
        type=Path,
        action="append",
        default=[],
        help="also write the reading as a measurement file (.cxf, .cgats, .csv, .xlsx; repeatable)",
    )
    cp.add_argument(
        "--format",
        choices=("cxf", "cgats", "csv", "xlsx"),
        help="format of --out (default: from its suffix)",
    )
    cp.add_argument("--sample", default="sample 1", help="sample name written to --out files")


def cmd_list(args: argparse.Namespace) -> dict[str, Any]:
    """List candidate devices."""
    from station.drivers.discovery import list_devices

    found, notes = list_devices()
    return {"devices": [d.to_dict() for d in found], "notes": notes}


@contextmanager
def _instrument(args: argparse.Namespace) -> Iterator[Any]:
    """The device of the command, opened through ``station.scan.open_device`` (closed on the way out)."""
    from station.scan import open_device

    if not (0.05 <= args.timeout <= 60):
        raise InputError("--timeout", "0.05 <= seconds <= 60", args.timeout)
    if args.design is not None and args.recipe is not None:
        raise InputError("--recipe", "either --design or --recipe, not both", str(args.recipe))
    if args.twelve and args.device.startswith("sim:") and args.device != "sim:ma6":
        raise InputError("--twelve", "only with sim:ma6", args.device)
    extra = ["--twelve"] if args.twelve else []
    with open_device(
        args.device,
        timeout_s=args.timeout,
        design_file=args.design,
        recipe_file=args.recipe,
        faults=args.fault,
        extra_args=extra,
    ) as device:
        yield device


@contextmanager
def _gloss_meter(args: argparse.Namespace) -> Iterator[Any]:
    """The ``--gloss`` meter (``station.scan.open_gloss_meter``), or ``None`` without ``--gloss``."""
    if getattr(args, "gloss", None) is None:
        yield None
        return
    from station.scan import open_gloss_meter

    with open_gloss_meter(args.gloss, timeout_s=args.timeout, field="--gloss") as meter:
        yield meter


def cmd_calibrate(args: argparse.Namespace) -> dict[str, Any]:
    """Calibrate step by step, asking for each reference first (``--yes``: without asking), and report it."""
    with _instrument(args) as device:
        inst = device.instrument
        (_name, r), *_ = calibrate_steps(args, device)
        return {
            "device": args.device,
            "address": f"{inst.family}@{inst.address}",
            "state": "calibrated",
            "calibration_id": r.calibration_id,
            "steps": list(r.steps),
            "verification_de": r.verification_de,
            "passed": r.passed,
            "expires": r.expires.isoformat() if r.expires else None,
        }


def calibrate_steps(args: argparse.Namespace, *devices: Any) -> list[tuple[str, Any]]:
    """Run the calibration steps of *devices* (``station.scan.CalibrationSession``) one at a time.

    Before each step its prompt goes to stderr and a line is read from stdin: empty or ``y`` runs the
    step, anything else (or end of input) cancels, and the command fails with one line saying the
    instrument is not calibrated. ``--yes`` runs every step without asking. A failed step raises
    ``station.scan.CalibrationStepError`` naming it.
    """
    from station.scan import CalibrationCancelled, CalibrationSession

    session = CalibrationSession(*devices)
    while (step := session.next) is not None:
        if not args.yes and not _confirm(step.prompt):
            session.cancel()
            raise CalibrationCancelled(step)
        print(f"reading the {step.title.lower()} of {step.device}…", file=sys.stderr)
        session.run_next()
    return session.results()


def _confirm(prompt: str) -> bool:
    """Show *prompt* on stderr and read the answer from stdin: go on (Enter, ``y``) or not."""
    sys.stderr.write(f"{prompt}\nPress Enter to read it (q to cancel): ")
    sys.stderr.flush()
    try:
        answer = sys.stdin.readline()
    except (OSError, ValueError):  # no usable stdin: nobody to confirm
        return False
    if not sys.stdin.isatty():  # an answer piped in is not echoed: end the prompt's line
        sys.stderr.write("\n")
    return answer != "" and answer.strip().lower() in ("", "y", "yes")


def _store_panel_id(panel: str | None) -> int | None:
    if panel is None:
        return None
    try:
        value = int(panel)
    except ValueError:
        value = 0
    if not 1 <= value <= 2**31 - 1:
        raise InputError("--panel", "with --store, a panel id 1 <= id <= 2147483647", panel)
    return value


@contextmanager
def _target(args: argparse.Namespace) -> Iterator[Any]:
    """The :class:`station.scan.DatabaseTarget` of the ``--store`` database (``None`` without ``--store``)."""
    if args.store is None:
        yield None
        return
    from db.engine import configured_database_url, data_dir
    from station.ingest import DatabaseDestination, Ingestor
    from station.scan import DatabaseTarget

    url = args.store or configured_database_url()
    destination = DatabaseDestination(url, migrate=True, source="cli")
    try:
        with Ingestor(destination, args.outbox or data_dir() / "measure-outbox.sqlite3") as ingestor:
            yield DatabaseTarget(ingestor)
    finally:
        destination.close()


def _receipt(target: Any, receipt: Any) -> dict[str, Any]:
    """The ``stored`` answer of a colour reading (a :class:`station.ingest.Receipt`)."""
    return {
        "status": receipt.status,
        "client_id": receipt.client_id,
        "measurement_id": receipt.measurement_id,
        "database": target.where,
        "outbox": str(target.ingestor.outbox.path),
        "message": receipt.message,
    }


def _gloss_receipt(target: Any, receipt: Any) -> dict[str, Any]:
    """The ``stored`` answer of a gloss reading (a :class:`station.scan.GlossReceipt`)."""
    return {
        "status": receipt.status,
        "client_id": receipt.client_id,
        "gloss_reading_id": receipt.gloss_reading_id,
        "database": target.where,
    }


def _stored(target: Any, result: Any) -> dict[str, Any]:
    """What became of the scan's records: the colour receipt (with its gloss reading's id), or the gloss one."""
    if result.receipt is None:
        return _gloss_receipt(target, result.gloss_receipt)
    out = _receipt(target, result.receipt)
    if result.gloss_receipt is not None:
        out["gloss_reading_id"] = result.gloss_receipt.gloss_reading_id
    return out


def _check_out_formats(args: argparse.Namespace) -> None:
    """Refuse ``--out`` files of no known format before the instrument is started."""
    from station.ingest.formats import FORMATS

    if args.format is not None and len(args.out) > 1:
        raise InputError(
            "--format", "one --out file with --format (or formats from the suffixes)", args.format
        )
    writable = [s for name, sfx in FORMATS.items() if name != "json" for s in sfx]
    for path in args.out:
        if args.format is None and path.suffix.lower() not in writable:
            raise InputError("--out", f"a file ending in {' | '.join(writable)} (or --format)", str(path))


def _write_files(reading: Any, args: argparse.Namespace) -> list[dict[str, str]]:
    """Write *reading* to each ``--out`` file (CxF3, CGATS.17 or the CSV template, docs/import.md)."""
    from station.ingest.formats import write_measurement_file
    from station.ingest.formats.measurement import from_spectral_reading

    if args.format is not None and len(args.out) > 1:
        raise InputError(
            "--format", "one --out file with --format (or formats from the suffixes)", args.format
        )
    measurement = from_spectral_reading(reading, args.sample)
    return [
        {"path": str(path), "format": write_measurement_file([measurement], path, args.format)}
        for path in args.out
    ]


def cmd_measure(args: argparse.Namespace) -> dict[str, Any]:
    """Measure once; spectra per geometry and Lab from the model, or gloss/haze/DOI; with ``--store``, store it.

    On a terminal a progress bar shows the steps (connecting — a simulator takes seconds to start —,
    measuring, converting or storing)."""
    panel_id = _store_panel_id(args.panel) if args.store is not None else None  # refused before starting
    _check_out_formats(args)
    with Steps(3, "measure") as steps:
        steps(f"connecting {args.device}")
        return _measure(args, panel_id, steps)


def _measure(args: argparse.Namespace, panel_id: int | None, steps: Steps) -> dict[str, Any]:
    from station import scan

    with _target(args) as target, _instrument(args) as device, _gloss_meter(args) as meter:
        if target is not None and args.client_id is not None:
            prior = scan.prior(target, args.client_id)
            if prior is not None:  # a retry: answered from the first attempt, nothing measured again
                stored = (
                    _gloss_receipt(target, prior)
                    if isinstance(prior, scan.GlossReceipt)
                    else _receipt(target, prior)
                )
                return {"device": args.device, "panel": args.panel, "stored": stored}
        calibrated = calibrate_steps(args, device, meter) if args.calibrate else []
        steps("measuring")
        inst = device.instrument
        result = scan.take(
            inst,
            None if meter is None else meter.instrument,
            device=args.device,
            gloss_device=args.gloss or "",
            gloss_field="--gloss",
        )
        steps("converting" if target is None else "storing")
        out: dict[str, Any] = {
            "device": args.device,
            "address": f"{inst.family}@{inst.address}",
            "panel": args.panel,
        }
        if calibrated:
            out["calibration"] = [{"device": n, "calibration_id": r.calibration_id} for n, r in calibrated]
        if result.gloss_only and result.gloss is not None:
            if args.out:
                raise InputError("--out", "a spectrophotometer reading (Lab per geometry)", args.device)
            out.update({"geometries": [], "lab": [], "spectra": [], **result.gloss.to_dict()})
        elif result.colour is not None:
            out.update(result.colour.to_dict())
            out["lab"] = result.lab.round(4).tolist()
            out["gloss_gu"] = result.gloss_60_gu
            if args.out:
                out["files"] = _write_files(result.colour, args)
        if target is not None:
            from station.ingest import operator_name

            result = scan.make_records(
                result,
                operator=operator_name(),
                illumination_deg=args.illumination,
                client_id=args.client_id,
                instrument=inst.identify() if result.colour is not None else None,
                panel_id=panel_id,
            )
            out["stored"] = _stored(target, scan.store(result, target))
        return out
