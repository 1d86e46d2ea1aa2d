"""Live telemetry for the ground station's operators: the telemetry table and the Foxglove live
view."""
