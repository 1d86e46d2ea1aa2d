"""The link stage the runtime declares (interfaces/runtime/link_stage.py): which messages cross
a modelled link, and the simulated radio (links/channel.py) as one the Bus can call."""

from __future__ import annotations

from interfaces.contracts.scenario import Comms
from interfaces.runtime.link_stage import LinkStage, crosses_link
from links.channel import ChannelModel


def test_which_messages_cross_a_link() -> None:
    assert crosses_link("sc1", "sc2") and crosses_link("sc3", "ground")
    assert crosses_link("ground", "sc1")
    assert not crosses_link("sim", "sc1") and not crosses_link("sc1", "sc1")
    assert not crosses_link(None, "sc1")


def test_the_channel_model_is_a_link_stage_whose_truth_one_bus_feeds() -> None:
    first = ChannelModel("sc1", Comms(range_m=50.0), seed=3)
    second = ChannelModel("sc2", Comms(range_m=50.0), seed=3, truth=first.truth)
    stage: LinkStage = first
    assert stage.truth_feed() is not None  # the first Bus of the process subscribes it
    assert second.truth_feed() is None  # the same history: fed once
    assert stage.delay_s == 0.0 and stage.released(10.0) == [] and stage.counters() == []
