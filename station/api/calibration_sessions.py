"""Calibration step by step over HTTP: the service's side of ``station.scan.CalibrationSession``.

A client starts a session for an attached spectrophotometer (and, optionally, an attached gloss meter);
the session lists every step with the prompt to show before it (black trap, white tile, verification
tile, gloss standard: :data:`station.scan.calibration.STEP_PROMPTS`). The client shows the prompt of
``next``, and once the operator has placed the instrument asks for that one step; between steps the
session's state is readable. When the last step passes, one calibration record per instrument is stored
(as the one-call calibration stores it) and the session reads ``calibrated``; a failed step ends it
``failed`` with the step and the reason named; a cancel ends it ``cancelled``. The instrument's own state
follows the protocol: a zero invalidates its white calibration, so a session that ends after its first
step without passing leaves the instrument needing calibration.

States: ``waiting`` (a step to prompt for), ``running`` (a step under way: a second step request is a
409), ``calibrated``, ``failed``, ``cancelled``. At most :data:`MAX_SESSIONS` sessions are kept; the oldest
ended one makes room for a new one, and when every kept session is still open a new one is a 409.
"""

from __future__ import annotations

import threading
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

from station.api.errors import ConflictError, NotFoundError
from station.api.schemas.instruments import CalibrationPublic, CalibrationSessionOut, CalibrationStepOut
from station.drivers import CalibrationResult
from station.errors import InputError
from station.scan import CalibrationSession, CalibrationStepError
from station.scan.devices import Device

__all__ = ["MAX_SESSIONS", "CalibrationSessions", "SessionState"]

#: Sessions kept (open and ended) by one service.
MAX_SESSIONS = 32

SessionState = Literal["waiting", "running", "calibrated", "failed", "cancelled"]
StepStatus = Literal["pending", "running", "passed", "failed"]
#: Stores the combined result of one instrument: ``(instrument id, result, reference) -> record``.
StoreCalibration = Callable[[str, CalibrationResult, str], CalibrationPublic]


@dataclass
class _Live:
    """One session and what the service knows of it (guarded by *lock*)."""

    id: uuid.UUID
    session: CalibrationSession
    reference: str
    lock: threading.Lock = field(default_factory=threading.Lock)
    state: SessionState = "waiting"
    error: str | None = None
    failed_step: int | None = None
    passed: int = 0
    records: list[CalibrationPublic] = field(default_factory=list)


class CalibrationSessions:
    """The step-wise calibration sessions of one service (see the module docstring)."""

    def __init__(self) -> None:
        self._sessions: dict[uuid.UUID, _Live] = {}
        self._lock = threading.Lock()

    def start(self, devices: list[Device], reference: str) -> CalibrationSessionOut:
        """A new session over *devices* (a spectrophotometer first, then a gloss meter if any)."""
        session = CalibrationSession(*devices)
        if not session.steps:
            raise InputError("instrument_id", "an instrument with calibration steps", devices[0].name)
        live = _Live(uuid.uuid4(), session, reference)
        with self._lock:
            if len(self._sessions) >= MAX_SESSIONS:
                ended = [k for k, s in self._sessions.items() if s.state not in ("waiting", "running")]
                if not ended:
                    raise ConflictError(
                        f"{MAX_SESSIONS} calibration sessions are open: finish or cancel one first"
                    )
                del self._sessions[ended[0]]  # dicts keep insertion order: the oldest ended one
            self._sessions[live.id] = live
        return self._out(live)

    def _get(self, session_id: uuid.UUID) -> _Live:
        with self._lock:
            live = self._sessions.get(session_id)
        if live is None:
            raise NotFoundError(f"calibration session {session_id} not found")
        return live

    def read(self, session_id: uuid.UUID) -> CalibrationSessionOut:
        """The session's state, its steps and the prompt of the next one."""
        return self._out(self._get(session_id))

    def step(self, session_id: uuid.UUID, store: StoreCalibration) -> CalibrationSessionOut:
        """Run the session's next step (the operator has placed the instrument as its prompt said).

        After the last step passes, *store* keeps one record per instrument. 409 when the session has
        ended or a step of it is running already.
        """
        live = self._get(session_id)
        with live.lock:
            if live.state != "waiting":
                raise ConflictError(f"calibration session {session_id} is {live.state}: no step to run")
            live.state = "running"
        step = live.session.next
        try:
            live.session.run_next()
        except CalibrationStepError as exc:
            with live.lock:
                live.state, live.error, live.failed_step = "failed", str(exc), exc.step.index
            return self._out(live)
        except BaseException:
            with live.lock:
                live.state, live.error = "failed", f"step {step.index if step else '?'} did not complete"
            raise
        with live.lock:
            live.passed += 1
        if live.session.next is None:
            try:
                records = [store(name, result, live.reference) for name, result in live.session.results()]
            except BaseException:  # every step passed but a record could not be stored: said, not hidden
                with live.lock:
                    live.state, live.error = "failed", "every step passed but the records were not stored"
                raise
            with live.lock:
                live.records, live.state = records, "calibrated"
        else:
            with live.lock:
                live.state = "waiting"
        return self._out(live)

    def cancel(self, session_id: uuid.UUID) -> CalibrationSessionOut:
        """End the session between steps, not calibrated; 409 while a step runs or once it has ended."""
        live = self._get(session_id)
        with live.lock:
            if live.state != "waiting":
                raise ConflictError(f"calibration session {session_id} is {live.state}: nothing to cancel")
            live.session.cancel()
            live.state = "cancelled"
        return self._out(live)

    def _out(self, live: _Live) -> CalibrationSessionOut:
        with live.lock:
            state, error, failed, records = live.state, live.error, live.failed_step, list(live.records)
            done = live.passed
        steps = []
        for s in live.session.steps:
            status: StepStatus
            if s.index <= done:
                status = "passed"
            elif failed == s.index:
                status = "failed"
            elif state == "running" and s.index == done + 1:
                status = "running"
            else:
                status = "pending"
            steps.append(
                CalibrationStepOut(
                    index=s.index,
                    total=s.total,
                    device=s.device,
                    step=s.step,
                    title=s.title,
                    prompt=s.prompt,
                    status=status,
                )
            )
        nxt = steps[done] if state in ("waiting", "running") and done < len(steps) else None
        return CalibrationSessionOut(
            id=live.id,
            state=state,
            next=nxt,
            steps=steps,
            error=error,
            records=records,
            calibrated=state == "calibrated",
        )
