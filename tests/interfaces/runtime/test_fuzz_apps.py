"""Every subscribed topic of every app, fuzzed (issue 16): random messages drawn from each
message's own JSON schema (so they pass validation: extreme values at the edges of the stated
physical ranges, odd combinations, any sender, any date), mixed with schema-breaking ones, sent
as bytes by a foreign endpoint to the app's real Bus, then a tick run on its real executive.

What must hold: the app goes on (its executive never stops; after the fuzz it still runs a tick),
no filter or map is poisoned (no float array an app holds gets a NaN), and every message
is accounted for (delivered, dropped as invalid, refused at admission, or still waiting for its
time)."""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from interfaces.contracts import topics
from interfaces.contracts.apps import GROUND_APPS, ONBOARD_FDIR_APPS, SPACECRAFT_APPS
from interfaces.contracts.messages import Message, Tick
from interfaces.runtime.app import App, AppContext, Input
from interfaces.runtime.assembly import app_class
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import Executive
from interfaces.runtime.transport import InprocNetwork
from tests.conftest import small_scenario

M = "fuzz"
SMALL = 6
"""Longest list drawn (POI lists, assignments...)."""


def from_schema(schema: dict[str, Any], defs: dict[str, Any]) -> st.SearchStrategy[Any]:
    """Values valid under a pydantic JSON schema, extremes of every range included."""
    if "$ref" in schema:
        return from_schema(defs[schema["$ref"].rsplit("/", 1)[-1]], defs)
    if "anyOf" in schema:
        return st.one_of([from_schema(s, defs) for s in schema["anyOf"]])
    if "const" in schema:
        return st.just(schema["const"])
    if "enum" in schema:
        return st.sampled_from(schema["enum"])
    kind = schema.get("type")
    if kind == "object":
        return _object(schema, defs)
    if kind == "array":
        items = from_schema(schema.get("items", {}), defs)
        low = schema.get("minItems", 0)
        return st.lists(items, min_size=low, max_size=max(low, min(schema.get("maxItems", SMALL),
                                                                    SMALL)))
    return _scalar(kind, schema)


def _scalar(kind: str | None, schema: dict[str, Any]) -> st.SearchStrategy[Any]:
    if kind == "integer":
        low, high = schema.get("minimum", -2**40), schema.get("maximum", 2**40)
        return st.one_of(st.sampled_from([low, high]), st.integers(low, high))
    if kind == "number":
        low = schema.get("minimum", schema.get("exclusiveMinimum", -1e12))
        high = schema.get("maximum", schema.get("exclusiveMaximum", 1e12))
        exclusive = "exclusiveMinimum" in schema, "exclusiveMaximum" in schema
        edges = [v for v, ex in ((low, exclusive[0]), (high, exclusive[1])) if not ex]
        floats = st.floats(low, high, allow_nan=False, allow_infinity=False,
                           exclude_min=exclusive[0], exclude_max=exclusive[1])
        return st.one_of(st.sampled_from(edges), floats) if edges else floats
    if kind == "string":
        return st.text(max_size=min(schema.get("maxLength", 12), 12))
    if kind == "boolean":
        return st.booleans()
    if kind == "null":
        return st.none()
    return st.none()


def _object(schema: dict[str, Any], defs: dict[str, Any]) -> st.SearchStrategy[Any]:
    props = schema.get("properties")
    if props is None:  # a dict of values
        values = from_schema(schema.get("additionalProperties", {}), defs)
        return st.dictionaries(st.text(max_size=8), values, max_size=SMALL)
    required = set(schema.get("required", []))
    return st.fixed_dictionaries(
        {k: from_schema(v, defs) for k, v in props.items() if k in required},
        optional={k: from_schema(v, defs) for k, v in props.items() if k not in required})


def message_payloads(msg_type: type[Message], owner: str) -> st.SearchStrategy[bytes]:
    """JSON payloads of ``msg_type``: schema-valid (sender mostly the key's owner, dates mostly
    near the run's clock), or broken (NaN, missing fields, garbage)."""
    schema = msg_type.model_json_schema()
    body = _object(schema, schema.get("$defs", {}))
    near = st.floats(0.0, 200.0)
    valid = st.tuples(body, st.sampled_from([owner, owner, owner, "sc9", "sim"]),
                      st.one_of(near, near, st.floats(0.0, 1e8))).map(
        lambda b: json.dumps({**b[0], "sender": b[1], "t_sim": b[2]}).encode())
    broken = st.one_of(
        body.map(lambda b: json.dumps({**b, "t_sim": math.nan}).encode()),
        st.just(b'{"sender": "x"}'), st.binary(max_size=40))
    return st.one_of(valid, valid, valid, broken)


def _apps() -> Iterator[tuple[type[App], str]]:
    yield from ((app_class(a), "sc1") for a in (*SPACECRAFT_APPS, *ONBOARD_FDIR_APPS))
    yield from ((app_class(a), topics.GROUND) for a in GROUND_APPS)


def _node(app_cls: type[App], node: str) -> tuple[Executive, App, Bus, object]:
    sc = small_scenario(M, duration_s=1e6, target={"pois": 200}, observers={"count": 2})
    net = InprocNetwork()
    bus = Bus(node, M, net.endpoint())
    ctx = AppContext(bus=bus, scenario=sc, node=node, spacecraft=topics.spacecraft_of(node),
                     rng=np.random.default_rng(0), log=logging.getLogger("fuzz"))
    app = app_cls(ctx)
    return Executive(bus, sc, [app], barrier_timeout_s=0.0), app, bus, net.endpoint()


def _key(inp: Input, node: str) -> tuple[str, str]:
    """A concrete key the input listens to, and the node that owns it."""
    publisher = "sc2" if inp.every_spacecraft else node
    key = inp.topic.key(M, publisher)
    return key, topics.node_of_key(key) or ""


def _finite(app: App) -> list[str]:
    """Names of the float arrays an app holds (one level into its objects) with a NaN in them
    (infinities are legitimate: an optimiser's open bounds).  What the apps publish is finite by
    schema, or it is not published."""
    bad = []
    for name, value in vars(app).items():
        inner = vars(value).items() if hasattr(value, "__dict__") and not isinstance(
            value, (type, np.ndarray)) else []
        for sub, arr in [(name, value), *((f"{name}.{k}", v) for k, v in inner)]:
            if isinstance(arr, np.ndarray) and arr.dtype.kind == "f" and np.isnan(arr).any():
                bad.append(sub)
    return bad


@pytest.mark.parametrize("app_cls,node", list(_apps()), ids=lambda v: getattr(v, "NAME", v))
@settings(max_examples=25, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_fuzzed_inputs_never_stop_or_poison_an_app(app_cls: type[App], node: str,
                                                   data: st.DataObject) -> None:
    executive, app, bus, raw = _node(app_cls, node)
    delivered: list[Message] = []
    for inp in app.INPUTS:  # a spy beside the app's own handler: what reached the app
        bus.subscribe(inp.key_expr(app.ctx), inp.msg_type, delivered.append)
    own: list[Message] = []  # what the app published itself (delivered locally, not received)
    publish = bus.publish
    bus.publish = lambda key, msg, announce=True: (own.append(msg),  # type: ignore[method-assign]
                                                   publish(key, msg, announce))
    for k in range(1, 4):
        for _ in range(data.draw(st.integers(1, 6))):
            inp = data.draw(st.sampled_from(app.INPUTS))
            key, owner = _key(inp, node)
            raw.publish(key, inp.msg_type.__name__,
                        data.draw(message_payloads(inp.msg_type, owner)))
        executive.run_tick(Tick(sender="sim", t_sim=50.0 * k, k=k, dt_s=0.5))
        assert _finite(app) == [], f"{app.NAME} holds non-finite state"
    stats, mine = bus.stats, {id(m) for m in own}
    received = [m for m in delivered if id(m) not in mine]
    waiting = [e for e in bus.inbox.pending if not e.local]  # after the last tick: not yet due
    assert stats.received == (len(received) + stats.invalid_dropped + stats.refused
                              + bus.admission.duplicates + len(waiting))
    # the node goes on: a tick after the fuzz still runs (an app's errors are counted, never
    # fatal) and leaves nothing poisoned
    errors = executive.app_errors + bus.stats.handler_errors
    executive.run_tick(Tick(sender="sim", t_sim=500.0, k=10, dt_s=0.5))
    assert executive.ticks == 4 and _finite(app) == []
    assert executive.app_errors + bus.stats.handler_errors == errors
