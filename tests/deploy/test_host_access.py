"""Access across hosts (deploy/host_access.py, docs/hosts.md): a router per host, the spokes
linked to the hub over TLS; every router enforces the run's rules, and the hub lets a spoke's
router publish only what that host's nodes may.  Two real routers in this process, on two
loopback addresses (the hub's own loopback listener left out: both cannot hold it in one
network namespace; separate namespaces in tests/missions/test_hosts_rehearsal.py)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zenoh
from cryptography import x509
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import NameOID

from deploy.access import access_control
from deploy.host_access import HostAccess, router_name, write_host_access
from deploy.host_map import HostMap, parse_host_map
from interfaces.contracts import topics
from interfaces.contracts.bundle import bundle_key
from tests.conftest import settle

M = "hx"


def _hosts(port: int) -> HostMap:
    return parse_host_map({"name": "t", "network": "127.0.0.0/24", "port": port, "hosts": [
        {"name": "ground", "address": "127.0.0.2", "nodes": ["ground", "recorder", "sim"]},
        {"name": "sca", "address": "127.0.0.3", "nodes": ["sc1", "sc2"]},
        {"name": "scb", "address": "127.0.0.4", "nodes": ["sc3"]}]}, "t")


def _read(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text())


def _open(config: dict[str, Any]) -> zenoh.Session:
    return zenoh.open(zenoh.Config.from_json5(json.dumps(config)))


def _at_hub(access: HostAccess, account_config: Path) -> dict[str, Any]:
    """An account's client configuration pointed at the hub over TLS."""
    config = _read(account_config)
    tlm = _read(access.tlm_config)
    config["connect"] = tlm["connect"]
    config["transport"]["link"] = tlm["transport"]["link"]
    return config


@pytest.fixture
def hosts(tmp_path: Path, free_port: int) -> Iterator[tuple[HostMap, HostAccess]]:
    host_map = _hosts(free_port)
    access = write_host_access(tmp_path / "access", M, 3, host_map)
    hub = _read(access.hosts["ground"].router_config)
    hub["listen"]["endpoints"] = [e for e in hub["listen"]["endpoints"] if e.startswith("tls/")]
    routers = [_open(hub), _open(_read(access.hosts["sca"].router_config))]
    yield host_map, access
    for r in routers:
        r.close()


def test_each_host_gets_its_own_folder_accounts_and_certificate(
        hosts: tuple[HostMap, HostAccess]) -> None:
    host_map, access = hosts
    assert sorted(access.hosts) == ["ground", "sca", "scb"]
    sca = access.hosts["sca"]
    users = {line.split(":")[0] for line in (sca.directory / "users.txt").read_text().split()}
    assert users == {"sc1", "sc2"}  # no other host's account, nor the watchers'
    hub_users = (access.hosts["ground"].directory / "users.txt").read_text()
    assert {line.split(":")[0] for line in hub_users.split()} == {
        "ground", "recorder", "sim", "tlm", "router-sca", "router-scb"}
    assert (sca.directory / "users.txt").stat().st_mode & 0o077 == 0
    cert = x509.load_pem_x509_certificate((sca.directory / "router.pem").read_bytes())
    assert cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value == "router-sca"
    names = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    assert [str(a) for a in names.get_values_for_type(x509.IPAddress)] == ["127.0.0.3"]
    authority = x509.load_pem_x509_certificate((sca.directory / "authority.pem").read_bytes())
    cert.verify_directly_issued_by(authority)
    assert isinstance(authority.public_key(), ec.EllipticCurvePublicKey)
    router = _read(sca.router_config)
    assert router["connect"]["endpoints"] == [f"tls/127.0.0.2:{host_map.port}"]
    assert router["transport"]["auth"]["usrpwd"]["user"] == router_name(host_map.hosts[1])
    assert _read(sca.client_config("sc1"))["connect"]["endpoints"] == [
        f"tcp/127.0.0.1:{host_map.port}"]
    assert _read(access.hosts["ground"].router_config)["connect"]["endpoints"] == []


def test_a_spokes_nodes_reach_the_hub_within_their_key_space_only(
        hosts: tuple[HostMap, HostAccess]) -> None:
    _, access = hosts
    sca = access.hosts["sca"]
    heard_at_hub: list[str] = []
    heard_at_sca: list[str] = []
    watcher = _open(_read(access.tlm_config))
    watcher.declare_subscriber(f"insp/{M}/**", lambda s: heard_at_hub.append(str(s.key_expr)))
    sc1 = _open(_read(sca.client_config("sc1")))
    sc2 = _open(_read(sca.client_config("sc2")))
    sc2.declare_subscriber(f"insp/{M}/**", lambda s: heard_at_sca.append(str(s.key_expr)))
    ground = _open(_at_hub(access, access.hosts["ground"].client_config("ground")))
    keys = [f"insp/{M}/sc/1/own", f"insp/{M}/sc/3/forged", f"insp/{M}/ground/forged"]
    settle(lambda: False, 1.0)  # subscriptions across the routers
    for key in keys:
        sc1.put(key, b"1")
    ground.put(f"insp/{M}/ground/own", b"1")
    ground.put(f"insp/{M}/sc/1/forged-by-ground", b"1")
    settle(lambda: len(heard_at_hub) >= 2 and len(heard_at_sca) >= 2, 5.0)
    settle(lambda: False, 0.5)
    assert sorted(heard_at_hub) == [f"insp/{M}/ground/own", f"insp/{M}/sc/1/own"]
    assert sorted(heard_at_sca) == [f"insp/{M}/ground/own", f"insp/{M}/sc/1/own"]
    for s in (watcher, sc1, sc2, ground):
        s.close()


def test_a_stolen_router_account_publishes_only_its_hosts_nodes(
        hosts: tuple[HostMap, HostAccess]) -> None:
    host_map, access = hosts
    heard: list[str] = []
    watcher = _open(_read(access.tlm_config))
    watcher.declare_subscriber(f"insp/{M}/**", lambda s: heard.append(str(s.key_expr)))
    relay = _read(access.hosts["sca"].router_config)["transport"]["auth"]["usrpwd"]
    thief = _at_hub(access, access.tlm_config)
    thief["transport"]["auth"]["usrpwd"] = {"user": relay["user"], "password": relay["password"]}
    stolen = _open(thief)
    settle(lambda: False, 0.5)
    stolen.put(f"insp/{M}/sc/2/as-sca", b"1")
    stolen.put(f"insp/{M}/sc/3/as-scb", b"1")
    stolen.put(f"insp/{M}/sim/as-sim", b"1")
    settle(lambda: bool(heard), 5.0)
    settle(lambda: False, 0.5)
    assert heard == [f"insp/{M}/sc/2/as-sca"]
    stolen.close()
    watcher.close()


def test_no_credentials_no_session_on_any_router(hosts: tuple[HostMap, HostAccess]) -> None:
    host_map, access = hosts
    for host in ("ground", "sca"):
        config = _at_hub(access, access.tlm_config)
        address = next(h.address for h in host_map.hosts if h.name == host)
        config["connect"]["endpoints"] = [f"tls/{address}:{host_map.port}"]
        del config["transport"]["auth"]
        with pytest.raises(zenoh.ZError):
            _open(config)
        config["transport"]["auth"] = {"usrpwd": {"user": "sc1", "password": "guess"}}
        with pytest.raises(zenoh.ZError):
            _open(config)


def test_a_relay_may_do_no_more_than_its_hosts_nodes() -> None:
    """The recorder on a spoke: the spoke's router may declare the recorder's token for it, and
    no more on that key (it lies in the ground's key space)."""
    acl = access_control(M, 2, relays={"router-x": ["sc1", "recorder"]})
    mine = {r["id"]: r for r in acl["rules"] if r["id"].startswith(("publish-router-x",
                                                                   "serve-router-x"))}
    assert mine["publish-router-x-0"]["key_exprs"] == [f"insp/{M}/sc/1/**"]
    assert "put" in mine["publish-router-x-0"]["messages"]
    assert mine["publish-router-x-1"]["messages"] == ["put"]  # sc1's bundles, alone
    assert mine["publish-router-x-1"]["key_exprs"] == [bundle_key(M, ["sc1"])]
    assert mine["publish-router-x-2"]["messages"] == ["liveliness_token"]
    assert mine["publish-router-x-2"]["key_exprs"] == [topics.recorder_token(M)]
    assert sorted(mine) == [f"{w}-router-x-{i}" for w in ("publish", "serve") for i in range(3)]
