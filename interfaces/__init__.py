"""What every process shares, in two rooms: the contracts (``interfaces.contracts``: messages,
topics, scenario models) and the runtime (``interfaces.runtime``: Bus, transports, executive).

Neither imports flight, sim or ground code; the runtime imports the contracts, never the
reverse.
"""
