"""The simulated radio between the nodes: the channel model (range, loss, delay, cuts), the
link faults, the space-ground link with its passes and the onboard stores.  The Bus calls it
through the link stage the runtime declares (``interfaces.runtime.link_stage``)."""
