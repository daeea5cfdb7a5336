"""The QC screen's model (Qt-free): jobs, a job's parts, the standard-vs-samples verdict table, reports.

Two sources give the same data: :class:`LocalQc` reads the workstation's database with
``station.qc`` (``station.qc.jobs.job_summary``, ``station.qc.report``), :class:`ServiceQc` asks a
station service's ``/api/v1/qc`` routes. A summary is the JSON form of
:class:`station.qc.jobs.JobSummary` (``to_dict()``), which is what the service answers too, so the
table rows (:func:`verdict_rows`) are built one way whatever the source. Each sample carries the gloss
reading paired with it (``station.ingest.gloss_of_measurements``), or ``None``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol
from urllib.parse import quote

from station.errors import InputError, StationError
from ui.models.local_db import LocalDatabase
from ui.models.qc_views import PLAIN, Judging, outlier_lines

if TYPE_CHECKING:
    from station.qc.jobs import JobSummary
    from station.qc.spc_part import PartSpc
    from ui.models.service import ServiceClient

#: Formulas offered, product default first (names as ``station.qc.check.formula_name`` accepts them).
FORMULAS = ("din6175-2", "cie2000", "cie94", "cie76")
REPORT_KINDS = ("pdf", "csv")
#: The gloss values a summary's sample carries (those of ``GET /api/v1/qc/jobs/{job}/summary``).
GLOSS_FIELDS = ("id", "gloss_20_gu", "gloss_60_gu", "gloss_85_gu", "haze_hu", "doi")


class QcSourceError(StationError):
    """The database or service could not answer (the message says which and why)."""


@dataclass(frozen=True)
class JobEntry:
    """A job and its parts."""

    job: str
    parts: tuple[str, ...]


@dataclass(frozen=True)
class VerdictRow:
    """One line of the verdict table: one sample at one geometry (differences sample − standard)."""

    measurement_id: int
    measured_at: str
    instrument: str
    geometry: str
    dl: float
    da: float
    db: float
    de: float
    verdict: str
    reason: str
    overall: str
    gloss_60_gu: float | None = None


class QcSource(Protocol):
    """Where the QC screen reads jobs and summaries and writes reports."""

    @property
    def where(self) -> str: ...
    def jobs(self) -> list[JobEntry]: ...
    def summary(
        self, job: str, formula: str, illuminant_limits: str | None = None, judging: Judging = PLAIN
    ) -> dict[str, Any]: ...
    def report(
        self,
        job: str,
        formula: str,
        kind: str,
        path: Path,
        illuminant_limits: str | None = None,
        judging: Judging = PLAIN,
    ) -> Path: ...
    def metamerism(self, standard_id: int, sample_id: int, formula: str) -> dict[str, Any]: ...
    def set_standard(self, job: str, part: str, measurement_id: int) -> None: ...
    def spc(
        self, job: str, part: str, formula: str, judging: Judging, baseline: int | None, subgroup: int
    ) -> PartSpc: ...
    def report_preview(
        self, job: str, formula: str, illuminant_limits: str | None = None, judging: Judging = PLAIN
    ) -> bytes: ...


class LocalQc(LocalDatabase):
    """The workstation's database (as ``station serve``: ``$CACAD_DATABASE_URL`` or the default SQLite)."""

    source_error = QcSourceError

    def jobs(self) -> list[JobEntry]:
        from station.qc.jobs import list_jobs

        with self._session() as session:
            return [JobEntry(j.job, tuple(j.parts)) for j in list_jobs(session)]

    def _summary(
        self,
        job: str,
        formula: str,
        illuminant_limits: str | None = None,
        judging: Judging = PLAIN,
        parts: list[str] | None = None,
    ) -> JobSummary:
        """``station.qc.jobs.job_summary`` as ``station qc summary`` calls it with the same options."""
        from station.qc.illuminant_rows import parse_illuminant_limits
        from station.qc.jobs import job_summary

        limits = None if illuminant_limits is None else parse_illuminant_limits(illuminant_limits)
        with self._session() as session:
            return job_summary(
                session,
                job,
                judging.tolerance_set(),
                formula,
                parts,
                judging.average_panels,
                illuminant_limits=limits,
                keep_outliers=judging.keep_outliers,
                texture_limits=judging.texture_tolerance(),
            )

    def summary(
        self, job: str, formula: str, illuminant_limits: str | None = None, judging: Judging = PLAIN
    ) -> dict[str, Any]:
        from station.ingest import gloss_of_measurements

        # the wire summary, with each sample's gloss added: a dict of the viewer's own
        data: dict[str, Any] = dict(self._summary(job, formula, illuminant_limits, judging).to_dict())
        samples = [s for p in data["parts"] for s in p["samples"]]
        with self._session() as session:
            gloss = gloss_of_measurements(session, [s["measurement_id"] for s in samples])
        for s in samples:
            g = gloss.get(s["measurement_id"])
            s["gloss"] = None if g is None else {k: getattr(g, k) for k in GLOSS_FIELDS}
        return data

    def report(
        self,
        job: str,
        formula: str,
        kind: str,
        path: Path,
        illuminant_limits: str | None = None,
        judging: Judging = PLAIN,
    ) -> Path:
        from station.qc import report

        summary = self._summary(job, formula, illuminant_limits, judging)
        return report.write_pdf(summary, path) if kind == "pdf" else report.write_csv(summary, path)

    def spc(
        self, job: str, part: str, formula: str, judging: Judging, baseline: int | None, subgroup: int
    ) -> PartSpc:
        """The part's SPC as ``station qc spc`` computes it (:func:`station.qc.spc_part.part_spc`)."""
        from station.qc.spc_part import part_spc

        return part_spc(self._summary(job, formula, None, judging, [part]), part, baseline, subgroup)

    def report_preview(
        self, job: str, formula: str, illuminant_limits: str | None = None, judging: Judging = PLAIN
    ) -> bytes:
        """The PDF report's first page as PNG bytes (:func:`ui.models.qc_views.report_first_page_png`)."""
        from ui.models.qc_views import report_first_page_png

        return report_first_page_png(self._summary(job, formula, illuminant_limits, judging))

    def metamerism(self, standard_id: int, sample_id: int, formula: str) -> dict[str, Any]:
        from db.models import Measurement
        from station.qc.metamerism import metamerism
        from station.qc.readings import reading_from_measurement

        with self._session() as session:
            rows = [session.get(Measurement, i) for i in (standard_id, sample_id)]
            if rows[0] is None or rows[1] is None:
                raise QcSourceError(f"{self.where}: measurement {standard_id} or {sample_id} not found")
            std, smp = (reading_from_measurement(m) for m in rows)
        return metamerism(std, smp, formula).to_dict()

    def set_standard(self, job: str, part: str, measurement_id: int) -> None:
        """Make measurement *measurement_id* the standard of *job*/*part*, replacing the one there."""
        from station.qc.jobs import set_standard

        with self._session() as session:
            set_standard(session, job, part, measurement_id=measurement_id, replace=True)
            session.commit()


class ServiceQc:
    """A station service's ``/api/v1/qc`` routes through the viewer's :class:`ServiceClient`."""

    def __init__(self, client: ServiceClient) -> None:
        self.client = client

    @property
    def where(self) -> str:
        return f"service {self.client.url}"

    def _get(self, path: str, **params: str) -> Any:
        from ui.models.service import ServiceError

        try:
            r = self.client.request("GET", path, params=params)
        except ServiceError as exc:
            raise QcSourceError(str(exc)) from exc
        if r.status_code >= 400:
            raise QcSourceError(f"{self.where}: {r.status_code} {r.text[:300]}")
        return r

    def jobs(self) -> list[JobEntry]:
        return [JobEntry(j["job"], tuple(j["parts"])) for j in self._get("/qc/jobs").json()]

    def _judged(
        self, path: str, formula: str, judging: Judging, illuminant_limits: str | None = None, **chart: Any
    ) -> Any:
        """*path* of a job judged under *judging*: ``GET`` with the summary's query (``average_panels``,
        ``keep_outliers``, ``texture_limits``, ``illuminant_limits``) and *chart* (SPC's ``part``,
        ``baseline``, ``subgroup``), or, with a tolerance file, ``POST`` with those and the tolerance set
        (as ``station qc tolerance --json`` writes it) in the body."""
        from ui.models.service import ServiceError

        options: dict[str, Any] = {"formula": formula, **{k: v for k, v in chart.items() if v is not None}}
        if judging.average_panels:
            options["average_panels"] = True
        if judging.keep_outliers:
            options["keep_outliers"] = True
        if judging.texture_limits.strip():
            options["texture_limits"] = judging.texture_limits.strip()
        if illuminant_limits is not None:
            options["illuminant_limits"] = illuminant_limits
        tolerance = judging.tolerance_set()
        if tolerance is None:
            query = {k: str(v).lower() if isinstance(v, bool) else str(v) for k, v in options.items()}
            return self._get(path, **query)
        try:
            r = self.client.request("POST", path, json={**options, "tolerance": tolerance.to_dict()})
        except ServiceError as exc:
            raise QcSourceError(str(exc)) from exc
        if r.status_code >= 400:
            raise QcSourceError(f"{self.where}: {r.status_code} {r.text[:300]}")
        return r

    def _unoffered(self, what: str) -> QcSourceError:
        return QcSourceError(
            f"{self.where}: {what}: available with the workstation's database only; "
            "the service's QC routes do not offer it"
        )

    def summary(
        self, job: str, formula: str, illuminant_limits: str | None = None, judging: Judging = PLAIN
    ) -> dict[str, Any]:
        return self._judged(
            f"/qc/jobs/{quote(job, safe='')}/summary", formula, judging, illuminant_limits
        ).json()

    def metamerism(self, standard_id: int, sample_id: int, formula: str) -> dict[str, Any]:
        from ui.models.service import ServiceError

        body = {
            "standard_measurement_id": standard_id,
            "sample_measurement_id": sample_id,
            "formula": formula,
        }
        try:
            r = self.client.request("POST", "/qc/metamerism", json=body)
        except ServiceError as exc:
            raise QcSourceError(str(exc)) from exc
        if r.status_code >= 400:
            raise QcSourceError(f"{self.where}: {r.status_code} {r.text[:300]}")
        return r.json()

    def set_standard(self, job: str, part: str, measurement_id: int) -> None:
        """``PUT /qc/jobs/{job}/standards/{part}`` with the measurement, replacing the one there."""
        from ui.models.service import ServiceError

        body = {"measurement_id": measurement_id, "replace": True}
        try:
            r = self.client.request(
                "PUT", f"/qc/jobs/{quote(job, safe='')}/standards/{quote(part, safe='')}", json=body
            )
        except ServiceError as exc:
            raise QcSourceError(str(exc)) from exc
        if r.status_code >= 400:
            raise QcSourceError(f"{self.where}: {r.status_code} {r.text[:300]}")

    def spc(
        self, job: str, part: str, formula: str, judging: Judging, baseline: int | None, subgroup: int
    ) -> PartSpc:
        """``GET /qc/jobs/{job}/spc`` judged as the table is: the service's ``station qc spc``."""
        from station.qc.spc_part import PartSpc

        path = f"/qc/jobs/{quote(job, safe='')}/spc"
        r = self._judged(path, formula, judging, part=part, baseline=baseline, subgroup=subgroup)
        return PartSpc.from_wire(r.json())

    def report_preview(
        self, job: str, formula: str, illuminant_limits: str | None = None, judging: Judging = PLAIN
    ) -> bytes:
        raise self._unoffered("the report preview")

    def report(
        self,
        job: str,
        formula: str,
        kind: str,
        path: Path,
        illuminant_limits: str | None = None,
        judging: Judging = PLAIN,
    ) -> Path:
        limits = illuminant_limits if kind == "pdf" else None
        r = self._judged(f"/qc/jobs/{quote(job, safe='')}/report.{kind}", formula, judging, limits)
        tmp = path.with_name(path.name + ".part")
        tmp.write_bytes(r.content)
        tmp.replace(path)
        return path


def verdict_rows(part: dict[str, Any]) -> list[VerdictRow]:
    """The table of one part of a summary: each sample at each geometry, oldest sample first."""
    rows: list[VerdictRow] = []
    for s in part.get("samples", []):
        qc = s["qc"]
        gloss = s.get("gloss") or {}
        g60 = gloss.get("gloss_60_gu")
        booth = (qc.get("illuminants") or {}).get("rows", [])
        for g in qc["per_geometry"]:
            verdict, reasons = str(g["verdict"]), list(g.get("reasons", []))
            for r in (r for r in booth if r["geometry"] == g["geometry"]):
                if r["verdict"] == "fail":  # an illuminant row over its limit fails the geometry
                    verdict = "fail"
                    reasons.append(str(r["text"]))
            rows.append(
                VerdictRow(
                    int(s["measurement_id"]),
                    str(s["measured_at"]),
                    str(s.get("instrument", "")),
                    str(g["geometry"]),
                    float(g["dL"]),
                    float(g["da"]),
                    float(g["db"]),
                    float(g["dE"]),
                    verdict,
                    "; ".join(reasons),
                    str(qc["verdict"]),
                    None if g60 is None else float(g60),
                )
            )
    return rows


class QcModel:
    """State of the QC screen: the jobs, the chosen job, part and formula, the summary shown."""

    def __init__(self, source: QcSource) -> None:
        self.source = source
        self.jobs: list[JobEntry] = []
        self.summary: dict[str, Any] | None = None
        self.summary_key: tuple[str, str] | None = None
        self.illuminant_limits: str | None = None
        self.judging = PLAIN

    def load_jobs(self) -> list[JobEntry]:
        """Read the jobs from the source (:class:`QcSourceError` when it cannot answer)."""
        try:
            self.jobs = self.source.jobs()
        except (QcSourceError, InputError):
            raise
        except Exception as exc:  # a database that cannot be opened: say where and why
            raise QcSourceError(f"{self.source.where}: {type(exc).__name__}: {exc}") from exc
        return self.jobs

    def parts_of(self, job: str) -> tuple[str, ...]:
        """The parts of *job* (empty when the job is unknown)."""
        return next((j.parts for j in self.jobs if j.job == job), ())

    def judge(
        self, job: str, formula: str, illuminant_limits: str = "", judging: Judging | None = None
    ) -> dict[str, Any]:
        """The summary of *job* in *formula* (every part); kept as :attr:`summary`.

        *illuminant_limits* (``"A=1.0,F11=1.5"``; blank for none) adds the illuminant rows
        (:mod:`station.qc.illuminant_rows`): a geometry whose row is over its limit fails, with the row
        as its reason. *judging* (:class:`~ui.models.qc_views.Judging`; the last one when ``None``):
        panels averaged with their outliers left out or kept, the tolerance file, texture limits."""
        if formula not in FORMULAS:
            raise InputError("formula", " | ".join(FORMULAS), formula)
        if not job:
            raise InputError("job", "a job (Load jobs lists them)", job)
        limits = illuminant_limits.strip() or None
        if limits is not None:
            from station.qc.illuminant_rows import parse_illuminant_limits

            parse_illuminant_limits(limits)  # a bad entry is named before the source is asked
        how = (self.judging if judging is None else judging).checked()
        self.summary = self.source.summary(job, formula, limits, how)
        self.summary_key = (job, formula)
        self.illuminant_limits = limits
        self.judging = how
        return self.summary

    def part(self, part: str) -> dict[str, Any] | None:
        """The summary's entry for *part*, or ``None``."""
        if self.summary is None:
            return None
        return next((p for p in self.summary["parts"] if p["part"] == part), None)

    def standard_candidates(self, part: str) -> list[tuple[int, str]]:
        """(measurement id, label) of every stored measurement of *part* in the judged job that could be
        its standard: its samples and its unjudged measurements, oldest first; the standard itself not."""
        p = self.part(part)
        if p is None:
            return []
        seen = {int(s["measurement_id"]): str(s["measured_at"])[:16].replace("T", " ") for s in p["samples"]}
        seen.update({int(i): "" for i in p.get("unjudged", []) if int(i) not in seen})
        std = p.get("standard") or {}
        seen.pop(int(std.get("measurement_id") or 0), None)
        return [(i, f"measurement {i}" + (f"  {when}" if when else "")) for i, when in sorted(seen.items())]

    def set_standard(self, part: str, measurement_id: int) -> dict[str, Any]:
        """Make *measurement_id* the standard of *part* of the judged job, then judge the job again (same
        formula and illuminant limits); the new summary. The id must be one of :meth:`standard_candidates`."""
        if self.summary_key is None:
            raise InputError("job", "a judged job (press Judge first)", None)
        ids = [i for i, _ in self.standard_candidates(part)]
        if measurement_id not in ids:
            raise InputError("standard", f"a measurement of {part}: one of {ids}", measurement_id)
        job, formula = self.summary_key
        self.source.set_standard(job, part, measurement_id)
        return self.judge(job, formula, self.illuminant_limits or "")

    def standard_text(self, part: str) -> str:
        """One line naming the part's standard and the pass/warn/fail counts."""
        p = self.part(part)
        if p is None:
            return "no summary"
        std = p.get("standard")
        if std is None:
            return f"{part}: no standard set (pick a measurement and press Set as standard)"
        ref = (
            f"measurement {std['measurement_id']}"
            if std.get("measurement_id")
            else f"design {std['design_id']}"
        )
        c = p["counts"]
        note = f"  — {p['note']}" if p.get("note") else ""
        return f"standard: {ref}   pass {c['pass']} · warn {c['warn']} · fail {c['fail']}{note}"

    def metamerism_text(self, part: str, sample_id: int) -> str:
        """The metamerism index (D65 → A, F11) of *sample_id* against *part*'s standard measurement, one line.

        The formula is the judged one's, except DIN 6175-2 (a tolerance formula): CIEDE2000 then.
        """
        p = self.part(part)
        std = None if p is None else p.get("standard")
        if std is None or not std.get("measurement_id"):
            raise InputError("standard", f"a standard measurement for {part} (a design has no spectra)", None)
        formula = self.summary_key[1] if self.summary_key else "cie2000"
        formula = "cie2000" if formula.startswith("din") else formula
        out = self.source.metamerism(int(std["measurement_id"]), sample_id, formula)
        mx = out["max_index"]
        return (
            f"metamerism of {sample_id} against {std['measurement_id']} ({out['formula']}): "
            + " · ".join(f"MI {ill} {v:.2f}" for ill, v in mx.items())
            + " (max over geometries)"
        )

    def report(self, kind: str, path: str | Path) -> Path:
        """Write the shown job's report (``pdf`` or ``csv``) at *path*."""
        if kind not in REPORT_KINDS:
            raise InputError("kind", " | ".join(REPORT_KINDS), kind)
        if self.summary_key is None:
            raise InputError("job", "a judged job (press Judge first)", None)
        job, formula = self.summary_key
        return self.source.report(job, formula, kind, Path(path), self.illuminant_limits, self.judging)

    def report_preview(self) -> bytes:
        """The shown job's PDF report, its first page as PNG bytes (as judged)."""
        if self.summary_key is None:
            raise InputError("job", "a judged job (press Judge first)", None)
        job, formula = self.summary_key
        return self.source.report_preview(job, formula, self.illuminant_limits, self.judging)

    def spc(self, part: str, baseline: int | None = None, subgroup: int = 1) -> PartSpc:
        """The SPC of *part* of the judged job, judged as the table is (``station qc spc`` with the same
        options): *baseline* points (subgroups) set the limits (all when ``None``), *subgroup* 1 is an
        individuals chart, 2 … 10 an X̄/R chart."""
        if self.summary_key is None:
            raise InputError("job", "a judged job (press Judge first)", None)
        job, formula = self.summary_key
        return self.source.spc(job, part, formula, self.judging, baseline, subgroup)

    def outliers_text(self, part: str) -> str:
        """The readings left out of (or flagged and kept in) the part's panel means, one per line."""
        p = self.part(part)
        if p is None or not self.judging.average_panels:
            return ""
        lines = outlier_lines(p)
        what = "kept (keep outliers on)" if self.judging.keep_outliers else "left out"
        return "\n".join(lines) if lines else f"panels averaged: no reading flagged, none {what}"
