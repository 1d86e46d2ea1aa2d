"""The GNC and information library that flight, sim and ground all use (no bus in it; it
imports nothing else of the project but the contracts):

* ``constants``: orbital constants; ``mission``: the mission's constants, computed once;
* ``hcw``: HCW relative motion and its discretisation; ``pro``: passive relative orbits (PRO);
* ``frames``: LVLH frames; ``quat``: quaternions; ``checks``: input checks of arrays;
* ``kalman``: linear Kalman steps; ``attitude_gains``: the attitude loop's gain design;
* ``infocost``: the information cost (Eq. 4-16), ``infocost_kernels`` its compiled precision
  kernel; ``poi``: the POIs; ``poi_map``: the POI map;
* ``passes``: the ground stations' contact windows;
* ``twin``: the nominal twin of an observer and the plan in force; ``fdi_metric``: the metric
  of Eq. 9, its direction and the global check (Eq. 6); ``hardware_threshold``: the ratio's
  nominal distribution from the hardware; ``window_test``: the window test the ground's FDIR
  and the neighbours' judge both run.

Flight-only algorithms (MPC, SCP, MEKF, attitude planning and control) stay in ``fsw.lib``.
"""
