"""Which test declared each of the ground's fault reports, and what its statistic and
threshold are called (summary.json ``detections[].test``; docs/fdir.md names the tests).

The ground declares a fault from one of these tests:

* a window's tests (``ground/fdir/information.py``, ``gnc/window_test.py``): the information
  test, H_m,i = |1 − ΔH_i/ΔH_i^pred| (Eq. 9) against the adaptive threshold τ_i (Eq. 11-12),
  or a test fused with it: the nav's NIS (Σ NIS of the window against its χ²(6N) quantile),
  the plan test (the nav's distance from the plan, m), the pointing test (reported pointing
  error, deg) or the Δv-rate test (m/s²);
* the sequential test at an image or nav update (``gnc/image_scan.py``): the image scan (the
  span's mean relative shift of ΔH_i/ΔH_i^pred against the shift it had to exceed), the NIS
  scan (the span's mean NIS per degree of freedom against its limit) or the pointing run
  (median pointing error against the tolerance, deg);
* the constellation's checks (``ground/fdir/global_check.py``): the global check (Eq. 6,
  |1 − ΣΔH_i/ΣΔH_i^pred| against its τ), or every observer's scans crossing together;
* the data-integrity check (|H_i reported / H_i from the observations − 1| against its
  tolerance), the link checks (the share of observations lost, a silence), or the
  neighbours aboard by agreement.

A report naming the class of a fault declared earlier in its episode is an identification,
not a declaration.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

from interfaces.contracts.messages import FaultReport, FdirWindow
from interfaces.contracts.scenario import FdirSettings

TestName = Literal["information", "nis", "plan", "pointing", "dv_rate", "image_scan",
                   "nis_scan", "pointing_scan", "global_check", "common_scans",
                   "data_integrity", "link", "neighbours", "identification"]
"""The test that declared a fault (module docstring)."""


@dataclass(frozen=True)
class TestLabel:
    """How a report names a test, its statistic and its threshold."""

    name: str
    statistic: str
    threshold: str


LABELS: Mapping[str, TestLabel] = MappingProxyType({
    "information": TestLabel("information test (Eq. 9)", "H_m,i", "τ_i"),
    "nis": TestLabel("window NIS test", "Σ NIS", "χ²(6N) quantile"),
    "plan": TestLabel("plan test", "nav from plan (m)", "tolerance (m)"),
    "pointing": TestLabel("pointing test", "pointing error (deg)", "tolerance (deg)"),
    "dv_rate": TestLabel("Δv-rate test", "Δv rate (m/s²)", "tolerance (m/s²)"),
    "image_scan": TestLabel("image scan (sequential)", "mean shift", "limit"),
    "nis_scan": TestLabel("NIS scan (sequential)", "mean NIS per dof", "limit"),
    "pointing_scan": TestLabel("pointing run (sequential)", "pointing error (deg)",
                               "tolerance (deg)"),
    "global_check": TestLabel("global check (Eq. 6)", "|1 − ΣΔH/ΣΔH_pred|", "τ"),
    "common_scans": TestLabel("scans of every observer together", "mean shift", "limit"),
    "data_integrity": TestLabel("data-integrity check", "H_i deviation", "tolerance"),
    "link": TestLabel("link check", "loss or silence", "limit"),
    "neighbours": TestLabel("neighbours aboard", "-", "-"),
    "identification": TestLabel("identification", "-", "-"),
})
"""Each test's label (:class:`TestLabel`), by :data:`TestName`."""

POSE_TESTS: Mapping[str, tuple[str, str]] = MappingProxyType({
    "plan": ("nav_vs_plan_m", "position_tol_m"),
    "pointing": ("pointing_error_deg", "pointing_tol_deg"),
    "dv_rate": ("dv_rate_mps2", "dv_rate_tol_mps2"),
})
"""A window's pose test: its statistic (the evidence's name) and its tolerance (the
``[fdir]`` setting's)."""


def report_test(report: FaultReport, window: FdirWindow | None) -> TestName:
    """The test that declared ``report`` (``window``: the window it was declared on, for a
    window's tests; None if not known)."""
    if report.cause is not None or (report.fault_class == "link" and not report.evidence):
        return "link"
    if report.spacecraft == 0:
        return "common_scans" if report.detector == "sequential" else "global_check"
    if report.detector == "sequential":
        return _scan_test(report.evidence)
    if report.fault_class == "data_integrity" and not report.evidence:
        return "data_integrity"
    failed: Sequence[str] = window.failed if window is not None else ("information",)
    if not failed:
        return "identification"
    return "information" if "information" in failed else failed[0]  # type: ignore[return-value]


def _scan_test(evidence: Mapping[str, float]) -> TestName:
    """The sequential test's part that declared (or, with ``since_s``, identified)."""
    if "since_s" in evidence:
        return "identification"
    if evidence.get("nis_scan"):
        return "nis_scan"
    return "pointing_scan" if evidence.get("pointing_scan") else "image_scan"


def declared_figures(test: TestName, report: FaultReport, window: FdirWindow | None,
                     cfg: FdirSettings) -> tuple[float | None, float | None]:
    """The statistic of ``test`` and the threshold it crossed: the report's own, but for a
    window declared by a test fused with the information test (its H_m,i then lay under τ_i),
    that test's: Σ NIS and its χ² quantile, or a pose test's evidence and tolerance."""
    if test == "nis" and window is not None:
        return window.nis_sum, window.nis_limit
    if test in POSE_TESTS:
        value, tol = POSE_TESTS[test]
        return report.evidence.get(value), float(getattr(cfg, tol))
    return report.metric, report.threshold
