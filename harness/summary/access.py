"""summary.json's ``access`` section: the router's audit of refused logins and messages
(``--audit-access``), from outside the archive."""

from __future__ import annotations

from pydantic import Field

from harness.summary.records import SummaryRecord


class AccessAudit(SummaryRecord):
    """``access``: the router's refusals when the run was audited (logs/access.json)."""

    refused: dict[str, int] = Field(description="refusals by kind")
    total: int = Field(ge=0)
