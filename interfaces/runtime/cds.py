"""A node process's critical-data store (after cFS's CDS): the file its state is written to at
every ω_mid boundary (``interfaces.runtime.restart``), and restored from when the launcher
starts the process again (docs/architecture.md, "Restarts").

* **Where.** ``<run>/cds/<node>.cds``, beside the run's key ``<run>/cds/key`` (made by the
  launcher: ``write_run_key``).  The folder is the owner's only (0700), the files too (0600).
* **Atomic.** The state is written to a temporary file of the same folder and renamed over the
  store: a kill leaves the last complete store or the one before, never half of one.  There is
  no fsync: the store outlives its process, not the machine.
* **Whose.** A header names the run (the key's fingerprint), the mission, the node, the seed
  and the scenario (a digest of it, overrides included), and the tick and sim time it holds.  A
  store whose header names another run, node, seed or scenario is refused.
* **Intact.** The header and the state are sealed with an HMAC-SHA256 under the run's key; a
  store that fails it (truncated, corrupted, forged) is refused.  Only then is the state
  unpickled: pickle is trusted with bytes this run wrote, nothing else.
* **Refused or missing.** The process starts cold; the launcher reads why from the starts
  record (``<node>.starts``, one JSON line per start: ``StartRecord``) and names it.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import pickle
import secrets
import struct
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Literal

from interfaces.contracts.scenario import Scenario
from interfaces.runtime.checkpoint import NodeState

MAGIC = b"INSPCDS1"
"""First bytes of a store (format 1)."""
KEY_FILE = "key"
KEY_BYTES = 32
_HEAD = struct.Struct(">8sI")  # magic, header length
_MAC_BYTES = 32


class StoreRefused(Exception):
    """The store cannot be restored from (the message says why); the process starts cold."""


def write_run_key(directory: Path) -> Path:
    """Make ``directory`` (0700) and the run's store key in it (random, 0600); the launcher
    does this once per run."""
    directory.mkdir(parents=True, exist_ok=True)
    directory.chmod(0o700)
    path = directory / KEY_FILE
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(secrets.token_bytes(KEY_BYTES))
    path.chmod(0o600)  # an existing file keeps its mode through O_TRUNC
    return path


@dataclass(frozen=True)
class StoreIdentity:
    """What a store belongs to (its header)."""

    run: str
    """Fingerprint of the run's key (not the key)."""
    mission: str
    node: str
    seed: int
    scenario: str
    """SHA-256 of the scenario as run (overrides included)."""

    @classmethod
    def of(cls, key: bytes, mission: str, node: str, scenario: Scenario) -> StoreIdentity:
        return cls(hashlib.sha256(b"run:" + key).hexdigest()[:16], mission, node,
                   scenario.seed, hashlib.sha256(scenario.model_dump_json().encode()).hexdigest())


@dataclass(frozen=True)
class StartRecord:
    """How a node process started: ``fresh`` (its first start: no store yet), ``restored``
    (from the store, at ``tick``) or ``cold`` (a restart that could not restore: ``reason``)."""

    outcome: Literal["fresh", "restored", "cold"]
    reason: str = ""
    tick: int = -1
    t_sim: float = 0.0
    wall_time: float = 0.0

    def describe(self) -> str:
        """E.g. ``restored after tick 1234 (t=123.4 s)``, ``cold start (store corrupted: ...)``."""
        if self.outcome == "restored":
            return f"restored after tick {self.tick} (t={self.t_sim:.1f} s)"
        return "cold start" + (f" ({self.reason})" if self.reason else "")


class CriticalDataStore:
    """The store of ``identity.node`` in ``directory`` (module docstring)."""

    def __init__(self, directory: Path, identity: StoreIdentity, key: bytes) -> None:
        self.directory, self.identity, self._key = directory, identity, key
        self.path = directory / f"{identity.node}.cds"
        self.starts_path = directory / f"{identity.node}.starts"
        self._tmp = directory / f".{identity.node}.cds.tmp"
        self.writes = 0

    @classmethod
    def open(cls, directory: Path, mission: str, node: str,
             scenario: Scenario) -> CriticalDataStore:
        """The store of ``node`` under the run's key in ``directory``; OSError if the key cannot
        be read."""
        key = (directory / KEY_FILE).read_bytes()
        if len(key) != KEY_BYTES:
            raise OSError(f"{directory / KEY_FILE} is not a store key ({len(key)} bytes)")
        return cls(directory, StoreIdentity.of(key, mission, node, scenario), key)

    # --- writing ---------------------------------------------------------------------------

    def save(self, state: NodeState, tick: int, t_sim: float) -> None:
        """Write ``state`` (after tick ``tick``, at ``t_sim`` s) atomically over the store."""
        body = pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)
        header = json.dumps({**asdict(self.identity), "tick": tick, "t_sim": t_sim,
                             "body_bytes": len(body)}).encode()
        head = _HEAD.pack(MAGIC, len(header)) + header
        mac = hmac.new(self._key, head + body, hashlib.sha256).digest()
        fd = os.open(self._tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "wb") as f:
            f.write(head + mac + body)
        os.replace(self._tmp, self.path)
        self.writes += 1

    # --- reading ---------------------------------------------------------------------------

    def load(self) -> tuple[NodeState, dict[str, object]]:
        """The state and the header of the store; :class:`StoreRefused` saying why not."""
        try:
            data = self.path.read_bytes()
        except FileNotFoundError:
            raise StoreRefused(f"no store at {self.path}") from None
        except OSError as e:
            raise StoreRefused(f"store unreadable: {e}") from None
        header, head_len = self._header(data)
        body = data[head_len + _MAC_BYTES:]
        if len(body) != header.get("body_bytes"):
            raise StoreRefused(f"store truncated: {len(body)} bytes of state, the header says "
                               f"{header.get('body_bytes')}")
        mac = hmac.new(self._key, data[:head_len] + body, hashlib.sha256).digest()
        if not hmac.compare_digest(mac, data[head_len:head_len + _MAC_BYTES]):
            raise StoreRefused("store corrupted: its seal does not match its contents")
        try:
            return pickle.loads(body), header
        except Exception as e:  # noqa: BLE001 - sealed but unreadable (a newer format)
            raise StoreRefused(f"store unreadable: {type(e).__name__}: {e}") from None

    def _header(self, data: bytes) -> tuple[dict[str, object], int]:
        """The header and the length of magic + header, checked against this store's
        identity."""
        if len(data) < _HEAD.size or not data.startswith(MAGIC):
            raise StoreRefused(f"not a store ({len(data)} bytes, no {MAGIC.decode()} mark): "
                               "truncated or corrupted")
        n = _HEAD.unpack_from(data)[1]
        try:
            header = json.loads(data[_HEAD.size:_HEAD.size + n])
            if not isinstance(header, dict):
                raise ValueError("not an object")
        except ValueError as e:
            raise StoreRefused(f"store header unreadable ({e}): truncated or corrupted") from None
        for name, mine in asdict(self.identity).items():
            if header.get(name) != mine:
                raise StoreRefused(f"store of another {name}: {header.get(name)!r}, this "
                                   f"{name} is {mine!r}")
        return header, _HEAD.size + n

    # --- the starts record -----------------------------------------------------------------

    def restarted(self) -> bool:
        """Whether this node's process started before in this run."""
        return self.starts_path.exists()

    def record_start(self, record: StartRecord) -> None:
        """Append how this process started to the starts record (0600)."""
        fd = os.open(self.starts_path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
        with os.fdopen(fd, "a", encoding="utf-8") as f:
            f.write(json.dumps(asdict(record)) + "\n")


def read_starts(path: Path) -> list[StartRecord]:
    """The starts record of a node (``[]`` if there is none; unreadable lines are skipped)."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError:
        return []
    out = []
    for line in lines:
        try:
            out.append(StartRecord(**json.loads(line)))
        except (ValueError, TypeError):
            continue
    return out
