"""A host map rehearsed on one machine (docs/hosts.md): a network namespace per host, their
links through one packet switch that delays, drops and cuts, torn down at the end."""
