"""Tools for people: live telemetry table, Foxglove live view."""
