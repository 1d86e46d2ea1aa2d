"""The whole constellation in one process on the in-process transport (tests, campaigns): every
node of the declared topology (``interfaces/contracts/topology.py``) and the sim.

Same apps, messages, channel model and lockstep as the multi-process run; ticks run
synchronously inside the sim's publish, so no threads are involved, and the spacecraft step
together as one fleet (``interfaces/runtime/fleet.py``).  The lean runtime: routes
resolved once per key, messages made in this process not re-admitted, one truth feed for every
node's channel stage, no barrier wait (every announced message was delivered before the tick).
The compiled kernels are loaded before the clock starts (``interfaces/runtime/kernels.py``), so
no rate group pays for their first call.
"""

from __future__ import annotations

import logging
import threading

from interfaces.contracts import topics
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.topology import topology
from interfaces.runtime.assembly import executive_of
from interfaces.runtime.blas_threads import one_blas_thread
from interfaces.runtime.bundle_out import BundleOut
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive, TickClient
from interfaces.runtime.fleet import fleets_of
from interfaces.runtime.heap import frozen_heap
from interfaces.runtime.kernels import compile_kernels
from interfaces.runtime.transport import InprocNetwork, RawHandler, SampleHandler
from links.channel import ChannelModel
from links.truth import history_for
from sim.node import SimNode


def run_inproc(
    scenario: Scenario,
    mission: str | None = None,
    tap: RawHandler | None = None,
    ground: bool = True,
    sample_tap: SampleHandler | None = None,
    stop: threading.Event | None = None,
    fleet: bool = True,
) -> tuple[SimNode, dict[str, Executive]]:
    """Run ``scenario`` to the end in this process.  ``tap`` receives every message raw (key,
    type, payload), as the recorder does; ``sample_tap`` every message as a Sample (the
    message object with its JSON bytes encoded on demand, once: the recorder's fast path).
    ``stop``, set, stops the run at the next tick boundary (``SimNode.completed`` stays
    False).  ``fleet``: the spacecraft step together (False: each alone, as it would in a
    process of its own).  Returns the sim and the executives by node.  This process's BLAS
    runs on one thread from then on (``interfaces.runtime.blas_threads``), and it holds the
    compiled kernels, loaded before the clock starts (``interfaces.runtime.kernels``)."""
    one_blas_thread()
    compile_kernels(logging.getLogger("insp.kernels").info)
    mission = mission or scenario.name
    net = InprocNetwork()
    if tap is not None:
        Bus("ground", mission, net.endpoint()).subscribe_raw(topics.mission_wildcard(mission), tap)
    if sample_tap is not None:
        net.endpoint().subscribe_samples(topics.mission_wildcard(mission), sample_tap)
    topo = topology(scenario, ground=ground)
    executives: dict[str, Executive] = {}
    truth = history_for(scenario)  # one truth feed for every node's channel
    for node in topo.nodes:
        bus = Bus(node.name, mission, net.endpoint(),  # no resend ring: nothing asks
                  channel=ChannelModel.of(node.name, scenario, truth), recent_ticks=0)
        executives[node.name] = executive_of(node, bus, scenario)
    fleets = fleets_of([n for n in topo.nodes if fleet and n.spacecraft is not None],
                       executives)
    for node in topo.nodes:  # the spacecraft step together (interfaces/runtime/fleet.py)
        fleet = fleets.get(node.name)
        TickClient(executives[node.name], synchronous=True,
                   fleet=fleet.take if fleet is not None else None)
    sim_bus = Bus(topics.SIM, mission, net.endpoint(), recent_ticks=0)
    # each fleet, node alone and the sim shares a bundle, as a process over Zenoh; in one
    # process nothing travels: the rows go one by one when its tick ends
    for buses in ([[m.bus for m in f.members] for f in {id(f): f for f in fleets.values()}.values()]
                  + [[e.bus] for n, e in executives.items() if n not in fleets] + [[sim_bus]]):
        BundleOut.share(buses, mission)
    sim = SimNode(sim_bus, scenario, topo.participants, log=logging.getLogger("insp.sim"),
                  stop=stop or threading.Event())
    with frozen_heap():  # what the start made is not walked by every full collection
        sim.run()
    return sim, executives

