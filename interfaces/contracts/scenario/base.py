"""What every scenario section is: a frozen pydantic model that refuses unknown keys (a typo
must not silently fall back to a default) and non-finite numbers."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class Section(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
