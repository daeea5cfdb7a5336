"""Analyses: seam QA of two panels (stored measurements or designs; stored and audited) and the stateless
misalignment computations (goniogeometric index, inverse trompe l'oeil, sweep) of ``station.analysis``."""

from __future__ import annotations

import tempfile
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import BaseModel
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import AnalysisResult, Measurement, User
from station.api.errors import NotFoundError
from station.api.schemas.analyses import (
    GgIndexEnvironmentRequest,
    GgIndexRequest,
    SeamQaCreate,
    SweepRequest,
    TrompeRequest,
)
from station.api.schemas.designs import DesignBody
from station.api.services import audit
from station.api.services.designs import to_design
from station.errors import InputError
from station.model import AspecularMeasurements
from station.model.domain import ILLUMINATION_DEG
from station.model.illuminants import illuminant_name
from station.model.spectra import WAVELENGTHS

if TYPE_CHECKING:
    from station.analysis.qa import SeamReport


def _aspecular(
    session: Session, measurement_id: int, illuminant: str = "D65", field: str = "measurement_id"
) -> AspecularMeasurements:
    m = session.get(Measurement, measurement_id)
    if m is None:
        raise NotFoundError(f"measurement {measurement_id} not found")
    if m.illumination_deg != ILLUMINATION_DEG:  # the seam analysis fits aspecular angles at 45°
        raise InputError(
            "measurement_id",
            f"a measurement of the {ILLUMINATION_DEG:g}° illumination block",
            f"measurement {m.id} ({m.illumination_deg:g}° illumination)",
        )
    order = np.argsort(m.geometries_deg)
    if illuminant_name(illuminant) != "D65":  # Lab under another light: from the spectra
        from station.analysis import measurements_under

        if not m.spectra or [float(w) for w in (m.wavelengths_nm or [])] != WAVELENGTHS.tolist():
            raise InputError(
                field,
                f"a measurement with spectra (400–700 nm, 10 nm) to judge under {illuminant_name(illuminant)}",
                f"measurement {m.id} (no such spectra)",
            )
        return measurements_under(
            [float(m.geometries_deg[i]) for i in order],
            np.asarray(m.spectra, dtype=float)[order],
            illuminant,
            m.gloss_gu,
            field=field,
        )
    return AspecularMeasurements(
        angles_deg=tuple(float(m.geometries_deg[i]) for i in order),
        lab=np.asarray(m.lab, dtype=float)[order],
        gloss_gu=m.gloss_gu,
        illuminant=m.illuminant,
        observer=m.observer,
    )


def _panel(
    session: Session, measurement_id: int | None, body: DesignBody | None, side: str, illuminant: str = "D65"
) -> Any:
    if measurement_id is not None:
        return _aspecular(session, measurement_id, illuminant, f"measurement_{side}")
    if body is None:  # the schema asks for exactly one source per panel
        raise InputError(f"design_{side}", f"measurement_{side} or design_{side}")
    return to_design(body, f"design_{side}")


#: Request fields passed to the ``station.analysis`` function of the same parameter name, as validated.
SEAM_OPTIONS = (
    "beta_deg",
    "lights_deg",
    "aspecular_deg",
    "tolerance",
    "method",
    "hinge",
    "objective",
    "illuminant",
)
INDEX_OPTIONS = ("epsilon", "method", "hinge", "direction", "beta_max_deg")
TROMPE_OPTIONS = ("beta_deg", "objective", "at", "subset", "hinge", "method", "epsilon", "allow_face_darker")
SWEEP_OPTIONS = ("hinge", "method", "epsilon")


def _options(request: BaseModel, names: tuple[str, ...]) -> dict[str, Any]:
    """The request's fields *names* by name, as validated (a numeric hinge azimuth as a float, degrees)."""
    out = {name: getattr(request, name) for name in names}
    if "hinge" in out and not isinstance(out["hinge"], str):
        out["hinge"] = float(out["hinge"])
    return out


def _seam_report(session: Session, request: SeamQaCreate) -> SeamReport:
    """Seam QA of the request's two panels (a stored measurement is fitted, eqs 3.3.x) at β."""
    from station.analysis import seam_qa as run_seam_qa

    a = _panel(session, request.measurement_a, request.design_a, "a", request.illuminant)
    b = _panel(session, request.measurement_b, request.design_b, "b", request.illuminant)
    return run_seam_qa(a, b, **_options(request, SEAM_OPTIONS))


def seam_qa(*, session: Session, actor: User, request: SeamQaCreate) -> AnalysisResult:
    """Fit measured panels (eqs 3.3.x) or take the designs, judge the seam at β and store the report."""
    from station.formulate.gamut import colorant_gamut

    report = _seam_report(session, request)
    result = report.to_dict()
    # flag a corrected paint outside the colorant gamut, with the nearest achievable paint
    result["corrected_colorant_gamut"] = colorant_gamut(report.correction.paint).to_dict()
    row = AnalysisResult(
        kind="seam_qa",
        inputs=request.model_dump(mode="json", by_alias=True, exclude_none=True),
        result=result,
        created_by_id=actor.id,
    )
    session.add(row)
    session.flush()
    audit.record(
        session=session,
        actor=actor,
        action="analysis.seam_qa",
        entity="analysis",
        entity_id=row.id,
        measurement_a=request.measurement_a,
        measurement_b=request.measurement_b,
        passed=report.passed,
    )
    session.commit()
    return row


_PLOT_LOCK = threading.Lock()  # matplotlib's pyplot state is process-wide: one report picture at a time


def report_png(*, session: Session, analysis_id: int) -> bytes:
    """The QA report picture of stored seam analysis *analysis_id* (panels as painted / corrected, and the
    Fig. 4.7 BRDF curves): the analysis is re-run from its stored inputs (deterministic) and plotted."""
    from station.analysis.picture import plot_seam_report

    row = get_analysis(session=session, analysis_id=analysis_id)
    if row.kind != "seam_qa":
        raise NotFoundError(f"analysis {analysis_id} is a {row.kind}, not a seam QA report")
    request = SeamQaCreate.model_validate(row.inputs)
    report = _seam_report(session, request)
    with tempfile.TemporaryDirectory(prefix="cacad-report-") as tmp, _PLOT_LOCK:
        return plot_seam_report(report, Path(tmp) / "report.png").read_bytes()


def gg_index(*, request: GgIndexRequest) -> dict[str, Any]:
    """Goniogeometric index (eq 4.3.1) as ``IndexResult.to_dict()``; nothing is stored."""
    from station.analysis import goniogeometric_index

    r = goniogeometric_index(
        to_design(request.paint, "paint"),
        request.lights_deg,
        request.views_deg,
        gloss=request.include_gloss,
        **_options(request, INDEX_OPTIONS),
    )
    return r.to_dict(per_geometry=request.per_geometry)


#: Width of the equirectangular map an environment is reduced to for the index (64 × 32 samples).
INDEX_ENV_WIDTH = 64


def gg_index_environment(*, request: GgIndexEnvironmentRequest) -> dict[str, Any]:
    """Environment-lit goniogeometric index (``station.analysis.index.environment_index``) as
    ``IndexResult.to_dict()`` plus the environment's name and sample count; nothing is stored. The map
    (built-in or uploaded, ``station.api.services.styling.request_environment``) is box-filtered to
    INDEX_ENV_WIDTH, turned by ``rotation_deg`` about +Y, and each pixel becomes a sample (direction,
    radiance × solid angle)."""
    import math

    import numpy as np

    from station.analysis.index import environment_index
    from station.api.services.styling import request_environment
    from station.render.cubemap import equirect_directions
    from station.render.truth import equirect_solid_angles

    env = request_environment(request.environment, request.environment_hdr)
    small = env.downsampled(INDEX_ENV_WIDTH) if env.equirect.shape[1] > INDEX_ENV_WIDTH else env
    img = np.asarray(small.equirect, dtype=float)
    h, w = img.shape[:2]
    e = equirect_directions(h, w).reshape(-1, 3)
    a = math.radians(request.rotation_deg)  # world = R_y(θ) · map direction (station.render.stage)
    rot = np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]])
    radiance = img.reshape(-1, 3) * equirect_solid_angles(h, w).reshape(-1, 1)
    keep = radiance.sum(axis=1) > 0.0
    r = environment_index(
        to_design(request.paint, "paint"),
        (e @ rot.T)[keep],
        radiance[keep],
        request.views_deg,
        panel=request.panel,
        gloss=request.include_gloss,
        **_options(request, INDEX_OPTIONS),
    )
    return {
        **r.to_dict(per_geometry=request.per_geometry),
        "environment": env.name,
        "samples": int(keep.sum()),
    }


def trompe_loeil(*, request: TrompeRequest) -> dict[str, Any]:
    """Inverse trompe l'oeil (§4.4) as ``TrompeResult.to_dict()``; nothing is stored."""
    from station.analysis.trompe import inverse_trompe_loeil

    paint = to_design(request.paint, "paint")
    r = inverse_trompe_loeil(
        paint, request.lights_deg, request.views_deg, **_options(request, TROMPE_OPTIONS)
    )
    return r.to_dict()


def sweep(*, request: SweepRequest) -> dict[str, Any]:
    """Seam ΔE over β × light × view (Fig. 4.3) as ``SweepResult.to_dict()``; nothing is stored."""
    from station.analysis.sweep import seam_sweep

    paint = to_design(request.paint, "paint")
    r = seam_sweep(
        paint, request.betas_deg, request.lights_deg, request.views_deg, **_options(request, SWEEP_OPTIONS)
    )
    return r.to_dict()


def get_analysis(*, session: Session, analysis_id: int) -> AnalysisResult:
    """Analysis *analysis_id*."""
    row = session.get(AnalysisResult, analysis_id)
    if row is None:
        raise NotFoundError(f"analysis {analysis_id} not found")
    return row


def list_analyses(
    *, session: Session, kind: str | None, limit: int, offset: int
) -> tuple[list[AnalysisResult], int]:
    """Analyses, newest first."""
    query = select(AnalysisResult)
    if kind:
        query = query.where(AnalysisResult.kind == kind)
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.scalars(query.order_by(AnalysisResult.id.desc()).limit(limit).offset(offset)).all()
    return list(rows), total
