"""Run archives as the ground station writes them: the recorder (``python -m
ground.archive.record``), its MCAP file layout, segments and the run metadata it writes.  Reading
them back is the harness's (``harness.archive``)."""
