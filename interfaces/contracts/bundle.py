"""Bundles: the hardware traffic of one process and tick as one message on the wire (issue 61;
docs/architecture.md, "Bundles").

What never passes the link stage (the catalogue's ``bundled`` topics: the tick and the truth,
the sim's hardware frames to the flight software, the commands back, the lockstep answers)
travels over Zenoh as one message per process and tick instead of one per key.  Each row is
still a whole message of its own key, stamped by its own node's Bus (sender, sequence number):
a receiver takes every row as if it had come alone (validated, admitted, the channel applied
by its key), and raw subscribers (the recorder, the live view) receive the rows, never the
bundle, so the archive's topics and messages are what they would be without bundles.

**The key names its process**: ``insp/<mission>/bundle/<node>-<node>-...``, the nodes the
publishing process hosts (``sim``; ``sc1-sc2-sc3``; ``ground``).  The process is the trust
boundary: the run's router lets only that process's account publish on that key
(``deploy/access.py``), and a receiver takes a row only if its key belongs to one of the nodes
the bundle's key names, in that node's own key space of the bundle's mission
(:func:`row_spaces`); any other row is refused and counted.

**Wire format** (type name ``Bundle``): one header line, the JSON array of rows
``[[key, type name, payload length in bytes], ...]``, then ``\\n``, then the rows' JSON payloads
back to back, exactly as each would have travelled alone.  A bundle whose header is longer
than :data:`MAX_HEADER_BYTES` (checked before it is parsed) or does not parse, has more than
:data:`MAX_ROWS` rows, a row key or type name too long, or lengths that do not add up to what
follows the header is dropped whole (:class:`BundleError`).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Final

from pydantic_core import from_json, to_json

from interfaces.contracts import topics

BUNDLE_TYPE: Final = "Bundle"
"""The type name a bundle travels with."""
BUNDLE_SPACE: Final = "bundle"
"""The key chunk after the mission that bundles live under."""
MAX_ROWS: Final = 4096
"""Rows a bundle may hold (a 10 Hz tick of 500 spacecraft needs about 1,500)."""
MAX_BUNDLE_BYTES: Final = 16 << 20
"""Bytes a bundle may hold (each row is held to the Bus's own limit besides)."""
MAX_HEADER_BYTES: Final = 1 << 20
"""Bytes a bundle's header line may hold, as one message (about 80 a row)."""
MAX_KEY_CHARS: Final = 1024
MAX_TYPE_CHARS: Final = 128
_SEPARATOR: Final = "-"

Row = tuple[str, str, bytes]
"""One message of a bundle: (key, type name, JSON payload)."""


class BundleError(ValueError):
    """A payload that is not a well-formed bundle (module docstring)."""


def bundle_key(mission: str, nodes: Iterable[str]) -> str:
    """The key a process hosting ``nodes`` publishes its bundles on."""
    names = list(nodes)
    if not names:
        raise ValueError("a bundle's process hosts at least one node")
    for n in names:
        topics.node_prefix(mission, n)  # a known node name, or ValueError
    return f"{topics.ROOT}/{mission}/{BUNDLE_SPACE}/{_SEPARATOR.join(names)}"


def bundle_space(mission: str) -> str:
    """Every bundle of ``mission`` (``*`` for any mission)."""
    return f"{topics.ROOT}/{mission}/{BUNDLE_SPACE}/*"


def is_bundle(key: str, type_name: str) -> bool:
    """Whether a sample on ``key`` of type ``type_name`` is a bundle."""
    return type_name == BUNDLE_TYPE and key.count("/") == 3 and key.split("/")[2] == BUNDLE_SPACE


def hosted_nodes(key: str) -> frozenset[str]:
    """The nodes the process publishing on bundle key ``key`` hosts (empty: not a bundle
    key)."""
    parts = key.split("/")
    if len(parts) != 4 or parts[0] != topics.ROOT or parts[2] != BUNDLE_SPACE:
        return frozenset()
    return frozenset(parts[3].split(_SEPARATOR))


def row_spaces(key: str) -> tuple[str, ...]:
    """The key spaces (``<node prefix>/``) the rows of a bundle on ``key`` may lie in: those of
    the nodes it names, in its mission (none for a key that is not a bundle's)."""
    parts = key.split("/")
    spaces = []
    for node in hosted_nodes(key):
        try:
            spaces.append(topics.node_prefix(parts[1], node) + "/")
        except ValueError:  # not a node's name, or not a mission's
            continue
    return tuple(spaces)


def row_admissible(spaces: tuple[str, ...], row_key: str) -> bool:
    """Whether a row on ``row_key`` lies in one of ``spaces`` (:func:`row_spaces`): exactly
    where the router would let its node put it alone."""
    return row_key.startswith(spaces)


def encode_bundle(rows: Iterable[Row]) -> bytes:
    """The wire bytes of ``rows`` (module docstring)."""
    rows = list(rows)
    header = to_json([(k, t, len(p)) for k, t, p in rows])
    return b"".join((header, b"\n", *(p for _, _, p in rows)))


def decode_bundle(payload: bytes) -> list[Row]:
    """The rows of a bundle's wire bytes; :class:`BundleError` if malformed."""
    if len(payload) > MAX_BUNDLE_BYTES:
        raise BundleError(f"{len(payload)} bytes exceed {MAX_BUNDLE_BYTES}")
    end = payload.find(b"\n", 0, MAX_HEADER_BYTES + 1)
    if end < 0:
        raise BundleError(f"no header line in its first {MAX_HEADER_BYTES} bytes")
    try:
        header = from_json(payload[:end], allow_inf_nan=False)
    except ValueError as e:
        raise BundleError(f"header is not JSON: {e}") from None
    if not isinstance(header, list) or len(header) > MAX_ROWS:
        raise BundleError(f"header is not a list of at most {MAX_ROWS} rows")
    rows: list[Row] = []
    at = end + 1
    for entry in header:
        key, type_name, size = _entry(entry)
        rows.append((key, type_name, payload[at:at + size]))
        at += size
    if at != len(payload):
        raise BundleError(f"row lengths add up to {at - end - 1} bytes, "
                          f"{len(payload) - end - 1} follow the header")
    return rows


def raw_rows(key: str, type_name: str, payload: bytes) -> list[Row]:
    """What a raw subscriber receives of a sample: a bundle's rows that its process may carry
    (:func:`row_admissible`), in order; anything else, a malformed bundle included, as it came
    (the recorder stores what does not parse as received)."""
    if not is_bundle(key, type_name):
        return [(key, type_name, payload)]
    try:
        rows = decode_bundle(payload)
    except BundleError:
        return [(key, type_name, payload)]
    spaces = row_spaces(key)
    return [r for r in rows if row_admissible(spaces, r[0])]


def _entry(entry: object) -> tuple[str, str, int]:
    """One header entry, checked: (key, type name, length)."""
    if not (isinstance(entry, list) and len(entry) == 3):
        raise BundleError(f"a row is [key, type, length], got {str(entry)[:80]!r}")
    key, type_name, size = entry
    if not (isinstance(key, str) and 0 < len(key) <= MAX_KEY_CHARS):
        raise BundleError(f"a row key must be a string of 1 to {MAX_KEY_CHARS} characters")
    if not (isinstance(type_name, str) and len(type_name) <= MAX_TYPE_CHARS):
        raise BundleError(f"a row type must be a string of at most {MAX_TYPE_CHARS} characters")
    if type(size) is not int or size < 0:
        raise BundleError(f"a row length must be a non-negative integer, got {size!r}")
    return key, type_name, size
