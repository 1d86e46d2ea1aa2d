"""The schema service on its own: a type's JSON schema by name, no reply for an unknown one."""

from __future__ import annotations

import json

from interfaces.contracts import topics
from interfaces.contracts.messages import Tick, json_schema
from interfaces.runtime.schemas import serve_schemas
from interfaces.runtime.transport import InprocNetwork


def test_each_type_is_served_by_name() -> None:
    net = InprocNetwork()
    serve_schemas(net.endpoint(), "sch", "ground")
    asker, prefix = net.endpoint(), topics.node_prefix("sch", "ground")
    [(_, reply)] = asker.query(f"{prefix}/schema/Tick")
    assert json.loads(reply) == json_schema(Tick)
    assert asker.query(f"{prefix}/schema/NoSuchType") == []
    assert asker.query(f"{topics.node_prefix('sch', 'sim')}/schema/Tick") == []
