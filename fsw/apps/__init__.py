"""Onboard apps.  Each declares its inputs, outputs and rate group at the top of its class."""
