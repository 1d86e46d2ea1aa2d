"""The schema service: a node answers queries on ``<node prefix>/schema/<Type>``
(``topics.schema_queryable``) with the JSON schema of the message type ``<Type>`` of the registry
(``interfaces.contracts.messages.registry``), as JSON bytes; an unknown type gets no reply.
"""

from __future__ import annotations

import json

from interfaces.contracts import topics
from interfaces.contracts.messages import json_schema, registry
from interfaces.runtime.transport import Transport


def serve_schemas(transport: Transport, mission: str, node: str) -> None:
    """Serve the schema queries of ``node`` in ``mission`` on ``transport``."""
    reg = registry()

    def respond(k: str) -> bytes | None:
        t = reg.get(k.rsplit("/", 1)[-1])
        return None if t is None else json.dumps(json_schema(t)).encode()

    transport.serve(topics.schema_queryable(mission, node), respond)
