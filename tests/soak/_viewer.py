"""A viewer, headless, scanning panels into the shared database until told to stop (the soak test's child).

Usage: ``python -m tests.soak._viewer URL OUTBOX LOG``. It does what a technician's viewer does, through
the viewer's own models (``ui.models``, no Qt): connects the MA6 simulator, stores every scan through a
:class:`~ui.models.measure_db.LocalSink` (outbox first) on the database *URL*, retries what an earlier
run left queued, and refreshes the QC screen's job list (:class:`~ui.models.qc.LocalQc`, which opens its
own engine) after each scan. Every scan's client id and Lab go to the sender log *LOG* before it is
stored, the receipt after. SIGTERM ends it after the scan in hand: the outbox is flushed, exit 0.
"""

from __future__ import annotations

import signal
import sys
import threading
import time
from types import FrameType

from tests.soak._log import SenderLog
from ui.models.instruments import InstrumentSession, MeasurementStore
from ui.models.measure_db import LocalSink, PanelInfo
from ui.models.qc import LocalQc

SENDER = "viewer"
PANEL = PanelInfo(job="SOAK-V", part="fender", notes="soak")
#: How long the last flush keeps retrying a busy database before the viewer gives up (seconds).
FLUSH_DEADLINE_S = 60.0


def _flush(sink: LocalSink, log: SenderLog) -> int:
    """Send what the outbox holds; log each receipt. Returns how many readings stay queued."""
    for receipt in sink.flush().values():
        log.ack(receipt.client_id, receipt.status, receipt.measurement_id)
    return sink.pending()


def main(argv: list[str]) -> int:
    url, outbox, log_path = argv[:3]
    stop = threading.Event()

    def _on_term(_sig: int, _frame: FrameType | None) -> None:
        stop.set()

    signal.signal(signal.SIGTERM, _on_term)
    sink = LocalSink(url, outbox)
    store = MeasurementStore(sink)
    instruments = InstrumentSession()
    qc = LocalQc(url)
    with SenderLog(log_path, SENDER) as log:
        try:
            sink.prepare()
            _flush(sink, log)  # "Retry queued": what a killed run left in the outbox
            instruments.connect("sim:ma6")
            print("ready", flush=True)
            while not stop.is_set():
                scan = instruments.scan(PANEL)
                if scan.reading is None:
                    print(f"scan not storable: {scan.note}", file=sys.stderr, flush=True)
                    return 1
                log.sent(str(scan.reading.client_id), scan.reading.lab)
                receipt = store.persist(scan).receipt
                if receipt is not None:
                    log.ack(receipt.client_id, receipt.status, receipt.measurement_id, scan.reading.lab)
                qc.jobs()  # the QC screen's job list, refreshed with the new reading
            end = time.monotonic() + FLUSH_DEADLINE_S
            while _flush(sink, log) and time.monotonic() < end:
                pass  # each try waits on the database lock (its busy timeout) before it gives up
            return 0 if sink.pending() == 0 else 3
        finally:
            instruments.close()
            sink.close()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
