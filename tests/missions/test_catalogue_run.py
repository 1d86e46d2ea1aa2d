"""The topic catalogue against a real (in-process) run: every message a run publishes is a
catalogued topic of its type, and every node subscribes to what its declarations say."""

from __future__ import annotations

from deploy.inproc import run_inproc
from interfaces.contracts import catalogue as cat
from interfaces.runtime.transport import Sample
from tests.conftest import small_scenario
from tests.interfaces.contracts.test_catalogue import declared_wiring


def test_a_run_publishes_and_subscribes_only_catalogued_topics() -> None:
    """The running constellation against the catalogue: every message sent is of its key's
    catalogue type, every node's subscriptions are what its declarations say."""
    published: dict[str, str] = {}

    def tap(sample: Sample) -> None:
        published.setdefault(sample.key, sample.type_name)

    scenario = small_scenario("cat", duration_s=12.0)
    sim, executives = run_inproc(scenario, sample_tap=tap)
    for key, type_name in published.items():
        topic = cat.topic_of(key)
        assert topic is not None, f"{key} is not catalogued"
        assert topic.type.__name__ == type_name, key
    seen = {cat.topic_of(k) for k in published}
    assert {cat.TICK, cat.TRUTH, cat.WHEELS, cat.NAV_ESTIMATE, cat.TICK_DONE} <= seen
    _, consumers = declared_wiring()
    for bus in [sim.bus, *(e.bus for e in executives.values())]:
        for expr, types in bus.subscriptions().items():
            topic = cat.topic_of(expr)
            assert topic is not None and topic in consumers, f"{bus.node} reads {expr}"
            assert set(types) == {topic.type}
