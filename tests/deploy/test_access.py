"""No stranger commands a spacecraft (issue 16, item 1): the run's router authenticates every
session and lets each account publish only in its own key space (deploy/access.py), over TCP
and TLS (forged messages during a real run: tests/missions/test_access_run.py)."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh

from deploy.access import RunAccess, write_run_access
from deploy.certificates import write_tls_files
from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.bundle import bundle_key
from tests.conftest import settle

M = "acc"


def _open(config: Path | dict) -> zenoh.Session:
    if isinstance(config, Path):
        return zenoh.open(zenoh.Config.from_file(str(config)))
    return zenoh.open(zenoh.Config.from_json5(json.dumps(config)))


@pytest.fixture
def network(tmp_path: Path, free_port: int) -> Iterator[RunAccess]:
    """A run's router (two observers) in this process, and its access files."""
    access = write_run_access(tmp_path / "access", M, 2, f"tcp/127.0.0.1:{free_port}")
    router = _open(access.router_config)
    yield access
    router.close()


def test_sessions_need_their_own_credentials(network: RunAccess) -> None:
    config = json.loads(network.client_config("tlm").read_text())
    for auth in (None, {"user": "tlm", "password": "guess"}, {"user": "root", "password": "x"}):
        forged = json.loads(json.dumps(config))
        if auth is None:
            del forged["transport"]["auth"]
        else:
            forged["transport"]["auth"]["usrpwd"] = auth
        with pytest.raises(zenoh.ZError):
            _open(forged)
    assert (network.directory / "users.txt").stat().st_mode & 0o077 == 0  # owner only
    assert network.client_config("sc1").stat().st_mode & 0o077 == 0


def test_each_account_publishes_only_in_its_own_key_space(network: RunAccess) -> None:
    sessions = {a: _open(network.client_config(a))
                for a in ("sim", "sc1", "sc2", "ground", "recorder", "tlm")}
    got: dict[str, list[str]] = {a: [] for a in ("sc2", "tlm", "recorder")}
    try:
        for a, keys in got.items():
            sessions[a].declare_subscriber(f"{topics.ROOT}/**",
                                           lambda s, keys=keys: keys.append(str(s.key_expr)))
        alive: list[str] = []
        sessions["sc2"].liveliness().declare_subscriber(
            f"{topics.ROOT}/{M}/**/alive", lambda s: alive.append(str(s.key_expr)), history=True)
        time.sleep(0.5)
        allowed = {"sim": cat.TICK.key(M), "sc1": cat.NAV_ESTIMATE.key(M, "sc1"),
                   "ground": cat.FAULT_REPORT.key(M)}
        forged = {"sc1": [cat.THRUST.key(M, "sc2"), cat.TICK.key(M), cat.FAULT_REPORT.key(M)],
                  "sc2": [cat.RELNAV.key(M, "sc1"), cat.TICK_DONE.key(M, "sc1")],
                  "tlm": [cat.WHEELS.key(M, "sc1"), cat.SIM_STATUS.key(M)],
                  "recorder": [cat.ASSIGNMENTS.key(M)]}
        for account, key in allowed.items():
            sessions[account].put(key, b"{}")
        for account, keys in forged.items():
            for key in keys:
                sessions[account].put(key, b"{}")
        sessions["sc1"].liveliness().declare_token(f"{topics.node_prefix(M, 'sc1')}/alive")
        sessions["tlm"].liveliness().declare_token(f"{topics.node_prefix(M, 'sc2')}/alive")
        settle(lambda: all(len(k) >= 3 for k in got.values()) and alive)
        time.sleep(0.3)
        # a session sees its own puts locally; through the router, only the allowed ones pass
        for account, keys in got.items():
            assert sorted(k for k in keys if k not in forged[account]) == sorted(
                allowed.values()), account
        assert set(alive) == {f"{topics.node_prefix(M, 'sc1')}/alive"}  # not the forged one
        # the read-only account can query what a node serves
        sessions["sc1"].declare_queryable(f"{topics.node_prefix(M, 'sc1')}/schema/**",
                                          lambda q: q.reply(str(q.key_expr), b"{}"))
        time.sleep(0.3)
        replies = list(sessions["tlm"].get(f"{topics.node_prefix(M, 'sc1')}/schema/X",
                                           timeout=2.0))
        assert [r.ok is not None for r in replies] == [True]
    finally:
        for s in sessions.values():
            s.close()


def test_tls_needs_the_runs_authority(tmp_path: Path, free_port: int) -> None:
    endpoint = f"tls/127.0.0.1:{free_port}"
    access = write_run_access(tmp_path / "access", M, 1, endpoint,
                              write_tls_files(tmp_path / "access" / "tls"))
    router = _open(access.router_config)
    try:
        good = _open(access.client_config("tlm"))
        good.close()
        config = json.loads(access.client_config("tlm").read_text())
        del config["transport"]["link"]  # no authority: the system's, which never signed it
        with pytest.raises(zenoh.ZError):
            _open(config)
        config["connect"]["endpoints"] = [f"tcp/127.0.0.1:{free_port}"]  # plain TCP to TLS
        with pytest.raises(zenoh.ZError):
            _open(config)
    finally:
        router.close()


def test_a_process_publishes_only_the_bundles_of_the_nodes_it_hosts(tmp_path: Path,
                                                                     free_port: int) -> None:
    """The bundle key names the nodes its rows may belong to (interfaces/contracts/bundle.py):
    the router lets only the first node of that process put on it, and a node alone its own."""
    access = write_run_access(tmp_path / "access", M, 3, f"tcp/127.0.0.1:{free_port}",
                              processes=[["sc1", "sc2"], ["sc3"], ["ground"]])
    router = _open(access.router_config)
    sessions = {a: _open(access.client_config(a)) for a in ("sim", "sc1", "sc2", "sc3", "tlm")}
    got: list[str] = []
    try:
        sessions["tlm"].declare_subscriber(f"{topics.ROOT}/**", lambda s: got.append(
            str(s.key_expr)))
        time.sleep(0.5)
        allowed = {"sim": bundle_key(M, ["sim"]), "sc1": bundle_key(M, ["sc1", "sc2"]),
                   "sc3": bundle_key(M, ["sc3"])}
        forged = {"sc2": [bundle_key(M, ["sc1", "sc2"]), bundle_key(M, ["sc2", "sc1"])],
                  "sc1": [bundle_key(M, ["sc1", "sc2", "sc3"]), bundle_key(M, ["sim"])],
                  "sc3": [bundle_key(M, ["sc3", "sc1"])]}
        for account, key in allowed.items():
            sessions[account].put(key, b"[]\n")
        for account, keys in forged.items():
            for key in keys:
                sessions[account].put(key, b"[]\n")
        settle(lambda: len(got) >= len(allowed))
        time.sleep(0.3)
        assert sorted(got) == sorted(allowed.values())
    finally:
        for s in sessions.values():
            s.close()
        router.close()
