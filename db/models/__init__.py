"""Every table of the measurement database (import this module to register them on ``Base``)."""

from db.models.designs import Design, DesignVersion
from db.models.gloss import GlossReading
from db.models.instruments import CalibrationRecord, Instrument
from db.models.library import JOB_STATES, AnalysisResult, FormulationJob, LibraryPaint
from db.models.measurements import PARTS, Measurement, Panel
from db.models.standards import Standard
from db.models.users import ApiToken, AuditEvent, LedgerHead, RecordEvent, Role, User

__all__ = [
    "JOB_STATES",
    "PARTS",
    "AnalysisResult",
    "ApiToken",
    "AuditEvent",
    "CalibrationRecord",
    "Design",
    "DesignVersion",
    "FormulationJob",
    "GlossReading",
    "Instrument",
    "LedgerHead",
    "LibraryPaint",
    "Measurement",
    "Panel",
    "RecordEvent",
    "Role",
    "Standard",
    "User",
]
