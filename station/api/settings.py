"""Service settings from the environment (``CACAD_*``) or an env file; built by the caller, never at import."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from pydantic import Field, computed_field, field_validator
from pydantic_settings import BaseSettings, NoDecode, SettingsConfigDict

from db.engine import data_dir, default_database_url

SIM_KINDS = ("ma6", "ma3", "gloss")


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
    load_demo_library: bool = Field(
        True, description="load station.formulate's demo library when the table is empty"
    )
    max_body_bytes: int = Field(
        1_048_576, ge=1024, le=64 * 1_048_576, description="request body cap (uploads)"
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
