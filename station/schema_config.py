"""The pydantic configuration of a model that is received (an API request body, a station's reading)."""

from __future__ import annotations

from collections.abc import Sequence

from pydantic import ConfigDict
from pydantic.config import JsonDict, JsonValue


def strict_config(*, examples: Sequence[JsonDict]) -> ConfigDict:
    """Unknown fields refused (``extra="forbid"``: a misspelt field is an error, never silently dropped), and
    *examples* shown in the JSON schema and the API docs."""
    shown: list[JsonValue] = [*examples]
    return ConfigDict(extra="forbid", json_schema_extra={"examples": shown})
