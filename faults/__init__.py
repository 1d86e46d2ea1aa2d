"""Fault injection: the test harness that switches a scenario's ``[[faults]]`` on and off
(docs/contracts.md, "Scenario TOML": kinds and magnitudes), in one place, by where each acts
(``schedule.py`` says when and where):

* ``hardware.py``: the sim's units (thrusters, wheels, cameras, the relative-navigation
  sensor), the faults a failing unit would cause; the sim hands its units to the injector;
* a spacecraft's links (``link_loss``, ``packet_loss``): the simulated radio's own
  (``links/faults.py``), applied by every receiving node's channel stage;
* ``software.py``: a spacecraft's own software (``faulty_data``: a corrupted H_i report),
  hooked in by its builder (``fsw/spacecraft.py``).

The package imports only the contracts and the shared library; flight, sim and ground code
never decide a fault, they are handed the part that acts where they run.
"""
