"""Fault injection: the test harness that switches a scenario's ``[[faults]]`` on and off
(docs/contracts.md, "Scenario TOML": kinds and magnitudes), in one place by where each acts.

* ``hardware.py``: the sim's units (thrusters, wheels, cameras, the relative-navigation
  sensor) -- the faults a failing unit would cause;
* ``software.py``: a spacecraft's own software (``faulty_data``: a corrupted H_i report);

Flight, sim and ground code never decide a fault: they are handed the injector that acts
where they run.
"""
