"""``fdir_series``: every window each detector decided, as named records in memory and as
positional arrays on disk (a run has thousands of them: named objects would triple the file).

On disk a baseline detector's row is ``[spacecraft, t_start_s, t_end_s, statistic,
threshold]``; the main detector's adds a sixth value, 1.0 when the window failed a test other
than the information test (0.0 otherwise).  Rows written before that flag existed have five
values: loading fills the flag in as False and names it (``MainWindow.FILLABLE``), and writing
such a row gives its five values back.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

from pydantic import Field, SerializerFunctionWrapHandler, model_serializer, model_validator

from harness.summary.records import SummaryRecord


class SeriesWindow(SummaryRecord):
    """One FDI window a baseline detector decided (ground/apps/baselines.py): its statistic
    against its threshold."""

    POSITIONS: ClassVar[tuple[str, ...]] = (
        "spacecraft", "t_start_s", "t_end_s", "statistic", "threshold")
    """The fields in the order of the row's values on disk."""

    spacecraft: int = Field(ge=0, description="the observer judged")
    t_start_s: float = Field(description="window start, sim s")
    t_end_s: float = Field(description="window end, sim s")
    statistic: float = Field(description="the detector's statistic (the main detector: H_m,i)")
    threshold: float = Field(description="the threshold it was compared with, same unit")

    @model_validator(mode="before")
    @classmethod
    def _from_row(cls, data: Any) -> Any:
        """A positional row (list or tuple) as its named fields."""
        if not isinstance(data, (list, tuple)):
            return data
        names = cls.POSITIONS
        least = len(names) - len(cls.FILLABLE)
        if not least <= len(data) <= len(names):
            count = f"{least} or {len(names)}" if least < len(names) else f"{len(names)}"
            raise ValueError(f"a row of {count} values ({', '.join(names)}) expected, "
                             f"got {len(data)}")
        return dict(zip(names, data, strict=False))  # an older row lacks the last columns

    @model_serializer(mode="plain")
    def _to_row(self) -> list[float | int]:
        return [self.spacecraft, self.t_start_s, self.t_end_s, self.statistic, self.threshold]

    def exceeded(self, scale: float = 1.0) -> bool:
        """Whether the window exceeds its threshold times ``scale``."""
        return self.statistic > scale * self.threshold


class MainWindow(SeriesWindow):
    """One FDI window the main detector decided: H_m,i against τ_i, and whether the window
    failed one of the other tests (plan, pointing, Δv rate, NIS: ``FdirWindow.failed``),
    which no threshold scale moves."""

    POSITIONS: ClassVar[tuple[str, ...]] = SeriesWindow.POSITIONS + ("other_tests_failed",)
    FILLABLE: ClassVar[tuple[str, ...]] = ("other_tests_failed",)

    other_tests_failed: bool = Field(
        default=False, description="failed a test other than the information test (on disk "
                                   "1.0 or 0.0; absent from rows written before it existed)")

    @model_serializer(mode="plain")
    def _to_row(self) -> list[float | int]:
        row: list[float | int] = [self.spacecraft, self.t_start_s, self.t_end_s,
                                  self.statistic, self.threshold]
        if "other_tests_failed" in self.model_fields_set:
            row.append(float(self.other_tests_failed))
        return row

    def exceeded(self, scale: float = 1.0) -> bool:
        """Whether the window is exceeded with the information threshold times ``scale``: H_m
        over it, or another test failed (at every scale)."""
        return self.other_tests_failed or super().exceeded(scale)


class FdirSeries(SummaryRecord):
    """``fdir_series``: the main detector's windows and each baseline's, in the order
    decided -- what a campaign needs to re-score at other threshold scales (ROC) without the
    archives.  On disk one object: ``{"main": [...], "<baseline>": [...], ...}``."""

    main: list[MainWindow] = Field(default_factory=list)
    baselines: dict[str, list[SeriesWindow]] = Field(
        default_factory=dict, description="by baseline detector (chi2_nis, cusum, ...)")

    @model_validator(mode="before")
    @classmethod
    def _from_disk(cls, data: Any) -> Any:
        """The on-disk object (detector name -> rows) as ``main`` and ``baselines``."""
        if not isinstance(data, dict) or "baselines" in data:
            return data
        rest = {k: v for k, v in data.items() if k != "main"}
        return ({"main": data["main"]} if "main" in data else {}) | {"baselines": rest}

    @model_serializer(mode="wrap")
    def _to_disk(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        d = handler(self)
        return ({"main": d["main"]} if "main" in d else {}) | d.get("baselines", {})

    def detectors(self) -> list[str]:
        """The detectors with a series: ``main`` (when recorded), then the baselines."""
        return (["main"] if "main" in self.model_fields_set else []) + list(self.baselines)

    def of(self, detector: str) -> Sequence[SeriesWindow]:
        """The windows of ``detector`` (``main`` or a baseline's name; none if unknown)."""
        return self.main if detector == "main" else self.baselines.get(detector, [])
