"""Run archives: the recorder, the reader, run metadata, the archive CLI
(``python -m ground.archive``)."""
