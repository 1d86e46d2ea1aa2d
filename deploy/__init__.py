"""Wiring of processes: run_constellation, campaigns, scenarios and Zenoh configs."""
