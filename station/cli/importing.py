"""``station import FILE`` and ``station import watch DIR``: vendor measurement files as a source.

* ``station import FILE [--format cxf|cgats|csv|xlsx] [--store [URL]] [--job J --part P] [--json]`` reads a
  CxF3, CGATS.17, MA-T12 workbook or CSV-template file (docs/import.md) and prints
  ``{"measurements": [{"geometries": [...], "lab": [[L,a,b], ...], "spectra": ..., "instrument": ...,
  "sample": ...}, ...]}``. With ``--store`` every measurement is stored through the one ingest path
  (``station.ingest.Ingestor`` into URL, by default the ``station serve`` database, queued in
  ``--outbox`` while it is away), one stored measurement per illumination block (an MA-T12-style file's
  45° and 15° blocks; ``--illumination`` stores one block only) with its vendor texture values, on the
  panel job/part/"sample: NAME" when ``--job`` and ``--part`` are given. Importing the same file again stores
  nothing new (client ids derive from the file's bytes).
* ``station import watch DIR [--once] [--interval S] [--settle S]`` (same store options) ingests each
  file dropped into DIR exactly once, moving it to ``DIR/done/``, or to ``DIR/rejected/`` with a
  ``NAME.reason`` file when it cannot be imported. ``--once`` processes what is there and exits.

A malformed file is refused with one line on stderr naming the file, the line or element and the
field, exit status 2, and nothing stored.
"""

from __future__ import annotations

import argparse
import json
import sys
import threading
from pathlib import Path
from typing import Any

from station.cli._common import add_json_flag
from station.errors import InputError


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station import``."""
    p = subparsers.add_parser(
        "import",
        help="import CxF3 / CGATS.17 / CSV measurement files, or watch a folder for them",
        description="station import FILE | station import watch DIR",
    )
    p.add_argument("target", nargs="+", metavar="FILE | watch DIR", help="a measurement file, or: watch DIR")
    p.add_argument(
        "--format",
        choices=("cxf", "cgats", "csv", "xlsx", "json"),
        help="file format (default: from suffix/content)",
    )
    p.add_argument(
        "--store",
        nargs="?",
        const="",
        metavar="URL",
        help="store the measurements in database URL (default: the `station serve` database)",
    )
    p.add_argument(
        "--outbox", type=Path, help="outbox file (default: measure-outbox.sqlite3 in the data folder)"
    )
    p.add_argument(
        "--out",
        type=Path,
        help="also write the measurements to FILE (.cxf, .cgats, .csv, .xlsx): a conversion",
    )
    p.add_argument("--job", help="job of the panels the measurements are stored on (with --part)")
    p.add_argument("--part", help="part of those panels (bumper, fender, door, …; with --job)")
    p.add_argument(
        "--illumination",
        type=float,
        default=None,
        help="store this illumination block only, degrees (default: every block of the file)",
    )
    p.add_argument("--once", action="store_true", help="watch: process the files there now, then exit")
    p.add_argument("--interval", type=float, default=1.0, help="watch: seconds between scans (default 1)")
    p.add_argument(
        "--settle", type=float, default=None, help="watch: seconds a file must be unchanged (default 2)"
    )
    p.add_argument(
        "--abandon",
        type=float,
        default=None,
        help="watch: seconds a file that is not whole may stay unchanged before it is rejected as "
        "incomplete (default 600)",
    )
    add_json_flag(p)
    p.set_defaults(handler=cmd_import)


def _measurement_json(m: Any, file: str, index: int) -> dict[str, Any]:
    import functools

    from station.ingest.errors import ImportFileError
    from station.ingest.formats import lab_of

    out = m.to_dict()
    out["lab_source"] = "file" if m.lab is not None else "spectra"
    where = f"measurement {index + 1} ({m.sample})"
    out["lab"] = lab_of(m, functools.partial(ImportFileError, file, where)).round(4).tolist()
    return out


def _panel(args: argparse.Namespace) -> tuple[str | None, str | None]:
    if (args.job is None) != (args.part is None):
        raise InputError("--job" if args.job is None else "--part", "--job J and --part P together")
    if args.job is not None and args.store is None and args.target[0] != "watch":
        raise InputError("--job", "with --store (the panel a stored measurement belongs to)", args.job)
    if args.part is not None:
        from db.models.measurements import PARTS

        if args.part not in PARTS:
            raise InputError("--part", " | ".join(PARTS), args.part)
    return args.job, args.part


def _illumination(args: argparse.Namespace) -> float | None:
    """The one illumination block to store (degrees), or ``None``: every block."""
    if args.illumination is None:
        return None
    if not 0 < args.illumination < 90:
        raise InputError("--illumination", "0 < degrees < 90", args.illumination)
    return float(args.illumination)


def cmd_import(args: argparse.Namespace) -> dict[str, Any] | None:
    """Import one file (optionally storing it) or watch a folder."""
    if args.target[0] == "watch" and len(args.target) == 2:
        return _watch(args)
    if len(args.target) != 1:
        raise InputError("FILE", "one measurement file, or: watch DIR", " ".join(args.target))
    job, part = _panel(args)

    from station.ingest.formats import load_measurement_file
    from station.ingest.formats.records import ImportOptions, readings_from_file

    path = Path(args.target[0])
    if not path.is_file():
        raise InputError("FILE", "an existing measurement file", str(path))
    imported, data = load_measurement_file(path, args.format)  # parsed and hashed from one read
    out: dict[str, Any] = {
        "format": imported.format,
        "file": imported.file,
        "measurements": [_measurement_json(m, imported.file, i) for i, m in enumerate(imported.measurements)],
    }
    if args.out is not None:
        from station.ingest.formats import write_measurement_file

        out["written"] = {
            "path": str(args.out),
            "format": write_measurement_file(imported.measurements, args.out),
        }
    if args.store is not None:
        from station.cli.instruments import _receipt, _target
        from station.ingest import operator_name

        options = ImportOptions(operator_name(), job, part, _illumination(args))
        # every reading validated before the first is stored
        readings = readings_from_file(imported, path, options, data=data)
        with _target(args) as target:
            out["stored"] = [
                _receipt(target, target.ingestor.submit(r)) | {"illumination_deg": r.illumination_deg}
                for r in readings
            ]
    if not args.json:
        for m in out["measurements"]:
            print(f"{m['sample']}: {len(m['geometries'])} geometries {', '.join(m['geometries'])}")
        if "written" in out:
            print(f"written: {out['written']['path']} ({out['written']['format']})")
        for r in out.get("stored", []):
            print(
                f"stored: {r['status']} {r['client_id']} measurement {r['measurement_id']}"
                f" ({r['illumination_deg']:g}° illumination)"
            )
        return None
    return out


def _watch(args: argparse.Namespace) -> dict[str, Any] | None:
    from station.cli.instruments import _target
    from station.ingest import operator_name
    from station.ingest.formats.records import ImportOptions
    from station.ingest.formats.watch import ABANDON_S, SETTLE_S, scan_once, watch_folder

    folder = Path(args.target[1])
    if not folder.is_dir():
        raise InputError("DIR", "an existing folder", str(folder))
    job, part = _panel(args)
    settle = SETTLE_S if args.settle is None else args.settle
    if not 0 <= settle <= 3600:
        raise InputError("--settle", "0 <= seconds <= 3600", settle)
    abandon = ABANDON_S if args.abandon is None else args.abandon
    if not settle < abandon <= 86400:
        raise InputError("--abandon", f"{settle:g} (--settle) < seconds <= 86400", abandon)
    if not 0.05 <= args.interval <= 3600:
        raise InputError("--interval", "0.05 <= seconds <= 3600", args.interval)
    if args.store is None:
        args.store = ""  # a watch folder always stores (default database)
    options = ImportOptions(operator_name(), job, part, _illumination(args))
    with _target(args) as target:
        ingestor = target.ingestor
        if args.once:
            outcomes = scan_once(folder, ingestor, options, settle_s=settle, abandon_s=abandon)
            result = {
                "folder": str(folder),
                "done": sum(o.status == "done" for o in outcomes),
                "rejected": sum(o.status == "rejected" for o in outcomes),
                "files": [o.to_dict() for o in outcomes],
            }
            if args.json:
                return result
            for o in outcomes:
                print(f"{o.status}: {o.file}" + (f" ({o.reason})" if o.reason else ""))
            return None

        def report(outcome: Any) -> None:
            line = json.dumps(outcome.to_dict()) if args.json else f"{outcome.status}: {outcome.file}"
            print(line, flush=True)

        stop = threading.Event()
        print(f"watching {folder} (Ctrl-C to stop)", file=sys.stderr, flush=True)
        try:
            watch_folder(
                folder,
                ingestor,
                options,
                interval_s=args.interval,
                settle_s=settle,
                stop=stop,
                on_outcome=report,
                abandon_s=abandon,
            )
        except KeyboardInterrupt:
            stop.set()
    return None
