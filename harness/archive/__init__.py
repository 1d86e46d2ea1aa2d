"""Reading run archives: the reader, sequence accounting, the scenario a run ran with, topic
DataFrames, and the archive command line (``python -m harness.archive``)."""
