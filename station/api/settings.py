"""Service settings from the environment (``CACAD_*``) or an env file; built by the caller, never at import."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from pydantic import Field, computed_field, field_validator, model_validator
from pydantic_settings import BaseSettings, NoDecode, SettingsConfigDict

from db.engine import data_dir, default_database_url
from station.drivers.families import SIM_DRIFT_SCALE_MAX, SIM_FAMILY_NAMES

#: File name, in the data folder, of the first admin token when ``station serve``'s output is not a terminal.
BOOTSTRAP_TOKEN_FILE = "bootstrap-token"


#: Default cap of simulator processes per station: one per simulated family (``station serve`` attaches
#: them all by default) and one more.
MAX_SIMULATORS_DEFAULT = len(SIM_FAMILY_NAMES) + 1


#: Default cap of a library upload: room for about 400 000 paints at six angles.
LIBRARY_UPLOAD_DEFAULT_BYTES = 64 * 1_048_576


class Settings(BaseSettings):
    """Everything the service needs to start; ``create_app(Settings(...))`` uses only this."""

    model_config = SettingsConfigDict(
        env_prefix="CACAD_", env_file=".env", env_ignore_empty=True, extra="ignore"
    )

    data_dir: Path = Field(default_factory=data_dir, description="workstation data folder")
    database_url: str | None = Field(None, description="SQLAlchemy URL; default: SQLite in data_dir")
    host: str = "127.0.0.1"
    port: int = Field(8000, ge=1, le=65535)
    auto_migrate: bool = Field(True, description="apply Alembic migrations on start")
    simulators: tuple[str, ...] = Field(("ma6",), description="simulators to spawn and attach on start")
    simulator_drift: float | None = Field(
        None,
        ge=0.0,
        le=SIM_DRIFT_SCALE_MAX,
        allow_inf_nan=False,
        description="scale of the simulators' stated drift across runs (their --drift: 1 = stated, 0 = none); "
        "default: theirs",
    )
    simulator_state_dir: Path | None = Field(
        None,
        description="folder of the simulators' run-state files, one per family (FAMILY.json, their --state): "
        "each start of a simulator is its next run, so its drift grows from one service start to the next",
    )
    max_simulators: int = Field(
        MAX_SIMULATORS_DEFAULT,
        ge=0,
        le=32,
        description="simulator processes (about 140 MiB each) this station runs at once, those "
        "attached on start included; a connect to sim:KIND beyond it is a 409 until one is detached",
    )
    load_demo_library: bool = Field(
        True, description="load station.formulate's demo library when the table is empty"
    )
    max_body_bytes: int = Field(
        1_048_576, ge=1024, le=64 * 1_048_576, description="request body cap (uploads)"
    )
    library_upload_max_bytes: int = Field(
        LIBRARY_UPLOAD_DEFAULT_BYTES,
        ge=1024,
        le=1024 * 1_048_576,
        description="body cap of a library CSV upload (POST /api/v1/library/import; a 50 000-paint "
        "library at six angles is about 7 MB); every other route keeps max_body_bytes",
    )
    image_decode_concurrency: int = Field(
        2,
        ge=1,
        le=64,
        description="uploads (eyedrop, sketch fit) decoded at once; others wait their turn",
    )
    public_docs: bool = Field(
        False,
        description="serve /docs, /redoc and /openapi.json without a token "
        "(default: they need a bearer token like every route but /health)",
    )
    instrument_hosts: Annotated[tuple[str, ...], NoDecode] = Field(
        (),
        description="hosts (HOST or HOST:PORT, comma-separated in CACAD_INSTRUMENT_HOSTS) that "
        "socket:// and rfc2217:// instrument addresses may name; empty: no TCP instruments",
    )
    outbox_replay_s: float = Field(10.0, gt=0, le=3600, description="seconds between outbox replay attempts")
    watch_dir: Path | None = Field(
        None,
        description="watch folder: measurement files (CxF3, CGATS.17, CSV template) dropped here are "
        "ingested once and moved to done/ or rejected/ (docs/import.md); unset: no watch folder",
    )
    watch_interval_s: float = Field(2.0, gt=0, le=3600, description="seconds between watch-folder scans")
    watch_job: str | None = Field(
        None, max_length=64, description="job of watch-folder panels (with watch_part)"
    )
    watch_part: str | None = Field(None, description="part of watch-folder panels (with watch_job)")
    body_timeout_s: float = Field(
        10.0, gt=0, le=600, description="seconds a client has to send a whole request body (else 408, closed)"
    )
    keep_alive_timeout_s: int = Field(
        5, ge=1, le=300, description="seconds an idle keep-alive connection stays open (uvicorn)"
    )
    limit_concurrency: int = Field(
        64,
        ge=1,
        le=10_000,
        description="requests handled at once before the server answers 503 (idle connections do not count)",
    )
    header_timeout_s: float = Field(
        10.0,
        gt=0,
        le=600,
        description="seconds a connection has, from its opening (on a kept-alive connection: from the first "
        "byte of each later request), to send a complete request line and headers (else 408 when it sent "
        "part of one, and closed)",
    )
    max_connections: int = Field(
        256,
        ge=1,
        le=10_000,
        description="open connections in all; a new one beyond closes the oldest idle one, or is refused "
        "(503) when every one is busy",
    )
    max_connections_per_client: int = Field(
        32,
        ge=1,
        le=10_000,
        description="open connections of one client address; a new one beyond closes that client's oldest "
        "idle one, or is refused (503) when every one is busy",
    )
    max_header_bytes: int = Field(
        16_384,
        ge=1024,
        le=1_048_576,
        description="most bytes of an unfinished request line and headers buffered (h11); beyond: 400",
    )
    token_ttl_days: float = Field(
        90.0, gt=0, le=3650, description="lifetime of a newly issued bearer token, in days"
    )
    token_recheck_s: float = Field(
        5.0,
        ge=0,
        le=300,
        description="seconds a token verified against the database is trusted before it is checked "
        "again (0: every request); a revocation made through this service applies at once, one made "
        "elsewhere (the CLI, another service) within this time",
    )
    token_offline_s: float = Field(
        900.0,
        ge=0,
        le=86_400,
        description="how long a token verified against the database keeps working while the database "
        "is away, in seconds (0: never without the database)",
    )

    @field_validator("instrument_hosts", mode="before")
    @classmethod
    def _split_hosts(cls, value: object) -> object:
        """A comma-separated string (the environment's form) becomes a tuple; each entry is checked."""
        from station.drivers.addresses import parse_host_entry

        if isinstance(value, str):
            value = tuple(e.strip() for e in value.split(",") if e.strip())
        if isinstance(value, (list, tuple)):
            for entry in value:
                if not isinstance(entry, str):
                    raise ValueError("instrument_hosts: expected HOST or HOST:PORT strings")
                parse_host_entry(entry)
        return value

    @field_validator("watch_part")
    @classmethod
    def _known_part(cls, value: str | None) -> str | None:
        from db.models.measurements import PARTS

        if value is not None and value not in PARTS:
            raise ValueError(f"watch_part: expected one of {' | '.join(PARTS)}, got {value!r}")
        return value

    @model_validator(mode="after")
    def _per_client_within_total(self) -> Settings:
        if self.max_connections_per_client > self.max_connections:
            raise ValueError(
                f"max_connections_per_client: expected at most max_connections ({self.max_connections}), "
                f"got {self.max_connections_per_client}"
            )
        return self

    @model_validator(mode="after")
    def _job_with_part(self) -> Settings:
        if (self.watch_job is None) != (self.watch_part is None):
            raise ValueError("watch_job and watch_part: expected both or neither")
        return self

    @computed_field  # type: ignore[prop-decorator]  # mypy rejects decorated properties; pydantic documents this
    @property
    def effective_database_url(self) -> str:
        """``database_url`` or the embedded SQLite file in ``data_dir``."""
        return self.database_url or default_database_url(self.data_dir)

    @computed_field  # type: ignore[prop-decorator]  # mypy rejects decorated properties; pydantic documents this
    @property
    def outbox_path(self) -> Path:
        """The ingest outbox of readings taken while the database is away."""
        return self.data_dir / "outbox.sqlite3"

    @computed_field  # type: ignore[prop-decorator]  # mypy rejects decorated properties; pydantic documents this
    @property
    def bootstrap_token_path(self) -> Path:
        """Where ``station serve`` writes the first admin token (0600) when its output is not a terminal."""
        return self.data_dir / BOOTSTRAP_TOKEN_FILE
