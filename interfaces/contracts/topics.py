"""Key expressions of the mission (docs/architecture.md): ``insp/<mission>/sc/<id>/<app>/<name>``,
``insp/<mission>/sim/...``, ``insp/<mission>/ground/...``.

A *node* is a process-level participant: ``"sim"``, ``"ground"`` or ``"sc<id>"``.  The node that
owns a key is read from the key itself (never from the message body), so the channel model and
access control both act on the key space.
"""

from __future__ import annotations

import re

ROOT = "insp"
SIM = "sim"
GROUND = "ground"
_SC_NODE = re.compile(r"^sc(\d+)$")
_SEGMENT = re.compile(r"^[A-Za-z0-9_\-]+$")


def sc_node(spacecraft: int) -> str:
    """Node name of spacecraft ``spacecraft`` (1-based)."""
    if spacecraft < 1:
        raise ValueError(f"spacecraft ids are 1-based, got {spacecraft}")
    return f"sc{spacecraft}"


def spacecraft_of(node: str) -> int | None:
    """Spacecraft id of a node name, or None for sim/ground/unknown."""
    m = _SC_NODE.match(node)
    return int(m.group(1)) if m else None


def node_prefix(mission: str, node: str) -> str:
    """Key space owned by ``node``: ``insp/<mission>/sc/<id>``, ``.../sim`` or ``.../ground``."""
    _check_segment(mission)
    sc = spacecraft_of(node)
    if sc is not None:
        return f"{ROOT}/{mission}/sc/{sc}"
    if node in (SIM, GROUND):
        return f"{ROOT}/{mission}/{node}"
    raise ValueError(f"unknown node {node!r}: expected 'sim', 'ground' or 'sc<N>'")


def node_of_key(key: str) -> str | None:
    """Owner node of a concrete key, or None if the key is outside the mission key spaces."""
    parts = key.split("/")
    if len(parts) < 3 or parts[0] != ROOT:
        return None
    if parts[2] == "sc" and len(parts) >= 4 and parts[3].isdigit():
        return f"sc{int(parts[3])}"
    if parts[2] in (SIM, GROUND):
        return parts[2]
    return None


def key(mission: str, node: str, *path: str) -> str:
    """Concrete key ``<node prefix>/<path...>``."""
    for p in path:
        _check_segment(p)
    return "/".join((node_prefix(mission, node), *path))


def mission_wildcard(mission: str) -> str:
    """Everything of a mission: ``insp/<mission>/**``."""
    _check_segment(mission)
    return f"{ROOT}/{mission}/**"


def all_spacecraft(mission: str, *path: str) -> str:
    """The same key on every spacecraft: ``insp/<mission>/sc/*/<path...>``."""
    _check_segment(mission)
    return "/".join((ROOT, mission, "sc", "*", *path))


# The message topics and their types are in ``interfaces.contracts.catalogue``; the keys below
# carry no message (services and liveliness).


def schema_queryable(mission: str, node: str) -> str:
    """Queryable serving message JSON schemas: ``<node prefix>/schema/*`` (by type name)."""
    return f"{node_prefix(mission, node)}/schema/*"


def recent_queryable(mission: str, node: str) -> str:
    """Queryable serving what ``node`` sent in its last ticks (``interfaces.runtime.recent``)."""
    return f"{node_prefix(mission, node)}/bus/recent"


def matches(key_expr: str, concrete: str) -> bool:
    """Whether a concrete key matches a key expression with ``*`` (one chunk) and ``**`` (any
    number of chunks, including none), as Zenoh defines them.  Used by the in-process transport
    so both transports route identically.
    """
    return _match(key_expr.split("/"), concrete.split("/"))


def _match(pat: list[str], key_parts: list[str]) -> bool:
    if not pat:
        return not key_parts
    head, rest = pat[0], pat[1:]
    if head == "**":
        return any(_match(rest, key_parts[i:]) for i in range(len(key_parts) + 1))
    if not key_parts:
        return False
    if head == "*" or head == key_parts[0]:
        return _match(rest, key_parts[1:])
    return False


def is_segment(s: str) -> bool:
    """Whether ``s`` may be one segment of a key (a mission's name): letters, digits, '_'
    or '-'."""
    return bool(_SEGMENT.match(s))


def _check_segment(s: str) -> None:
    if not _SEGMENT.match(s):
        raise ValueError(f"invalid key segment {s!r}: use letters, digits, '_' or '-'")


def alive_token(mission: str, node: str) -> str:
    """Liveliness token of a lockstep node (the sim, a spacecraft, the ground)."""
    return f"{node_prefix(mission, node)}/alive"


RECORDER = "recorder"
"""The recorder, as its liveliness token names it (not a lockstep node: no key space)."""


def recorder_token(mission: str) -> str:
    """Liveliness token of the recorder (not a lockstep node)."""
    return key(mission, GROUND, RECORDER, "alive")
