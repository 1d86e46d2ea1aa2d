"""The experiment harness: what is not a ground station.  A run's summary.json and its sections
(``harness.summary``), report.md (``harness.report``), campaign statistics, reports and studies
(``harness.campaign``), the archive's readers and exports (``harness.archive``) and the FDIR
replayed on an archive (``harness.replay``).  It imports anything; no flying code imports it."""
