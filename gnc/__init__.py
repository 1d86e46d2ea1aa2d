"""The GNC and information library that flight, sim and ground all use: orbital constants, HCW
relative motion and its discretisation, passive relative orbits (PRO), LVLH frames, quaternions,
linear Kalman steps, the attitude loop's gain design, the information cost (Eq. 4-16) and its
compiled precision kernel, the POIs and the POI map.  No bus in it; it imports nothing else of
the project but the contracts.

Flight-only algorithms (MPC, SCP, MEKF, attitude planning and control) stay in ``fsw.lib``.
"""
