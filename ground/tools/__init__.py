"""Tools for people: live telemetry table, Foxglove live view, the FDIR replayed on an archive."""
