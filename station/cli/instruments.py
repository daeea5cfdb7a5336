"""``station instruments list``, ``station calibrate DEVICE``, ``station measure DEVICE``.

DEVICE is ``sim:ma6`` / ``sim:ma3`` / ``sim:gloss`` (a simulator subprocess started for the command;
``--design FILE`` or ``--recipe FILE`` — ``station formulate --json`` output — sets its panel) or an address accepted by :func:`station.drivers.open_instrument`
(``/dev/ttyACM0``, ``ma3@usb:1209:ca03``, ``gloss@hid:PATH`` …). Lab comes from
``station.model.spectra.reflectance_to_lab`` (D65, CIE 1964 10°), never from the driver.

``station measure DEVICE --store [URL]`` also stores the reading: the record is
``station.ingest.record_from_reading``'s and it goes through ``station.ingest.Ingestor`` (exactly once by
client id; queued in ``--outbox`` when the database is away and sent by the next ``--store``) into URL,
or by default the database ``station serve`` uses (``$CACAD_DATABASE_URL``, else ``station.sqlite3`` in
``$CACAD_DATA_DIR`` or ``./var``), upgraded to the current schema on first use. A gloss meter's reading
(20/60/85 GU, haze, DOI, Rspec) is stored as a gloss-only reading (``station.ingest.store_gloss``) on the
``--panel`` given, directly (not queued): the QC views pair it with a colour reading of the same panel.

``station measure DEVICE --out FILE [--out FILE …] [--format cxf|cgats|csv|xlsx] [--sample NAME]`` also
writes the reading (every geometry, spectra and Lab) as a CxF3, CGATS.17, MA-T12 workbook or CSV file that
``station import`` reads (docs/import.md): how the simulators write each vendor format.
"""

from __future__ import annotations

import argparse
import uuid
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
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
        ("calibrate", cmd_calibrate, "zero, white and verification calibration"),
        ("measure", cmd_measure, "measure once and print spectra, Lab and gloss"),
    ):
        cp = subparsers.add_parser(name, help=text)
        cp.add_argument("device", help="sim:ma6 | sim:ma3 | sim:gloss | an address (see docs/protocols)")
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
        if name == "measure":
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
        add_json_flag(cp)
        cp.set_defaults(handler=fn)


def cmd_list(args: argparse.Namespace) -> dict[str, Any]:
    """List candidate devices."""
    from station.drivers.discovery import list_devices

    found, notes = list_devices()
    return {"devices": [d.to_dict() for d in found], "notes": notes}


@contextmanager
def _instrument(args: argparse.Namespace) -> Iterator[Any]:
    from station.drivers import open_instrument
    from station.drivers.simproc import SIM_KINDS, spawn_simulator

    if not (0.05 <= args.timeout <= 60):
        raise InputError("--timeout", "0.05 <= seconds <= 60", args.timeout)
    with ExitStack() as stack:
        address = args.device
        if args.device.startswith("sim:"):
            kind = args.device[4:]
            if kind not in SIM_KINDS:
                raise InputError("device", "sim:ma6 | sim:ma3 | sim:gloss or an address", args.device)
            if args.design is not None and args.recipe is not None:
                raise InputError("--recipe", "either --design or --recipe, not both", str(args.recipe))
            if args.twelve and kind != "ma6":
                raise InputError("--twelve", "only with sim:ma6", args.device)
            extra = ["--twelve"] if args.twelve else []
            design = None if args.design is None else args.design.resolve()  # the child runs elsewhere
            recipe = None if args.recipe is None else args.recipe.resolve()
            sim = stack.enter_context(
                spawn_simulator(kind, design, args.fault, recipe_file=recipe, extra_args=extra)
            )
            address = sim.address
        elif args.design is not None or args.recipe is not None or args.fault or args.twelve:
            raise InputError("--design/--recipe/--fault/--twelve", "only with a sim:* device", args.device)
        inst = stack.enter_context(open_instrument(address, timeout_s=args.timeout))
        yield inst


def cmd_calibrate(args: argparse.Namespace) -> dict[str, Any]:
    """Run the calibration sequence and report it."""
    with _instrument(args) as inst:
        r = inst.calibrate()
        return {
            "device": args.device,
            "address": f"{inst.family}@{inst.address}",
            "calibration_id": r.calibration_id,
            "steps": list(r.steps),
            "verification_de": r.verification_de,
            "passed": r.passed,
            "expires": r.expires.isoformat() if r.expires else None,
        }


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
def _ingestor(args: argparse.Namespace) -> Iterator[Any]:
    """The :class:`~station.ingest.Ingestor` into the ``--store`` database (``None`` without ``--store``)."""
    if args.store is None:
        yield None
        return
    from db.engine import configured_database_url, data_dir
    from station.ingest import DatabaseDestination, Ingestor

    url = args.store or configured_database_url()
    destination = DatabaseDestination(url, migrate=True, source="cli")
    try:
        with Ingestor(destination, args.outbox or data_dir() / "measure-outbox.sqlite3") as ingestor:
            yield ingestor
    finally:
        destination.close()


def _receipt(ingestor: Any, receipt: Any) -> dict[str, Any]:
    return {
        "status": receipt.status,
        "client_id": receipt.client_id,
        "measurement_id": receipt.measurement_id,
        "database": ingestor.destination.where,
        "outbox": str(ingestor.outbox.path),
        "message": receipt.message,
    }


def _stored_gloss_id(ingestor: Any, client_id: uuid.UUID) -> int | None:
    """The gloss reading stored under *client_id* in the ``--store`` database, or ``None``."""
    from sqlalchemy import select

    from db.models import GlossReading as GlossRow

    with ingestor.destination.sessions()() as session:
        found = session.scalar(select(GlossRow.id).where(GlossRow.client_id == client_id))
    return None if found is None else int(found)


def _gloss_receipt(ingestor: Any, client_id: uuid.UUID, gloss_id: int, status: str) -> dict[str, Any]:
    return {
        "status": status,
        "client_id": str(client_id),
        "gloss_reading_id": gloss_id,
        "database": ingestor.destination.where,
    }


def _store_gloss(
    ingestor: Any, reading: Any, panel_id: int | None, client_id: uuid.UUID | None
) -> dict[str, Any]:
    """Store a gloss-only reading (``station.ingest.store_gloss``) straight in the ``--store`` database.

    Gloss readings do not go through the outbox: with the database away this fails and stores nothing.
    """
    from station.ingest import gloss_record_from_reading, operator_name, store_gloss

    record = gloss_record_from_reading(
        reading, operator=operator_name(), client_id=client_id, panel_id=panel_id
    )
    with ingestor.destination.sessions().begin() as session:
        result = store_gloss(session, record)
    status = "stored" if result.created else "duplicate"
    return _gloss_receipt(ingestor, record.client_id, result.measurement_id, status)


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
    from station.drivers import GlossReading

    with _ingestor(args) as ingestor, _instrument(args) as inst:
        if ingestor is not None and args.client_id is not None:
            ingestor.replay()
            prior = ingestor.find(args.client_id)
            if prior is not None:  # a retry: answered from the first attempt, nothing measured again
                return {"device": args.device, "panel": args.panel, "stored": _receipt(ingestor, prior)}
            gloss_prior = _stored_gloss_id(ingestor, args.client_id)
            if gloss_prior is not None:
                stored = _gloss_receipt(ingestor, args.client_id, gloss_prior, "duplicate")
                return {"device": args.device, "panel": args.panel, "stored": stored}
        steps("measuring")
        reading = inst.measure()
        steps("converting" if ingestor is None else "storing")
        out: dict[str, Any] = {
            "device": args.device,
            "address": f"{inst.family}@{inst.address}",
            "panel": args.panel,
        }
        if isinstance(reading, GlossReading):
            if args.out:
                raise InputError("--out", "a spectrophotometer reading (Lab per geometry)", args.device)
            data = reading.to_dict()
            out.update({"geometries": [], "lab": [], "spectra": [], **data})
            if ingestor is not None:
                out["stored"] = _store_gloss(ingestor, reading, panel_id, args.client_id)
            return out
        from station.model.spectra import reflectance_to_lab

        data = reading.to_dict()
        out.update(data)
        out["lab"] = reflectance_to_lab(reading.reflectance).round(4).tolist()
        out["gloss_gu"] = None
        if args.out:
            out["files"] = _write_files(reading, args)
        if ingestor is not None:
            from station.ingest import operator_name, record_from_reading

            record = record_from_reading(
                reading,
                operator=operator_name(),
                illumination_deg=args.illumination,
                client_id=args.client_id,
                instrument=inst.identify(),
                panel_id=panel_id,
            )
            out["stored"] = _receipt(ingestor, ingestor.submit(record))
        return out
