"""Offline analysis of run archives: summary, report, coverage, nav and GNC evaluation, scoring,
calibration, campaign report."""
