"""``run_constellation.py --hosts`` (docs/hosts.md): bad combinations and maps refused before
anything starts, naming what is wrong; without ``--rehearse``, each host's files and commands
printed (the rehearsal itself: tests/missions/test_hosts_rehearsal.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from deploy.cli import main
from tests.conftest import REPO

LAB = str(REPO / "deploy" / "hosts" / "lab.toml")


def _refused(argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    out = tmp_path / "out"
    assert main(["run", *argv, "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err


@pytest.mark.parametrize("argv, says", [
    (["--hosts", LAB, "--transport", "inproc"], "not with --transport inproc"),
    (["--hosts", LAB, "--external", "sc3"], "not with --external"),
    (["--hosts", LAB, "--restart-on-crash"], "--restart-on-crash (not rehearsed across hosts)"),
    (["--rehearse"], "--rehearse apply only with --hosts"),
    (["--link-delay-ms", "5", "--link-loss-pct", "1"],
     "--link-delay-ms, --link-loss-pct apply only with --hosts"),
    (["--hosts", LAB, "--link-event", "sca:cut:10:5"], "applies only to a rehearsal"),
    (["--hosts", LAB, "--rehearse", "--link-event", "sca:cut:10"], "expected HOST:cut"),
    (["--hosts", LAB, "--rehearse", "--link-event", "ground:cut:10:5"], "ground is the hub"),
    (["--hosts", LAB, "--rehearse", "--link-event", "scz:cut:10:5"], "no host 'scz'"),
    (["--hosts", LAB, "--link-delay-ms", "-1"], "greater than or equal to 0"),
    (["--hosts", str(REPO / "deploy" / "hosts" / "trio.toml")], "sc3, sc4, sc5"),
    (["--hosts", "none.toml"], "cannot read host map none.toml"),
])
def test_bad_host_options_are_refused_before_anything_starts(
        argv: list[str], says: str, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    assert says in _refused(argv, tmp_path, capsys)


def test_on_real_machines_each_hosts_files_and_commands_are_printed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "lab"
    assert main(["run", "--hosts", LAB, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    for host, address in (("ground", "10.77.0.1"), ("sim", "10.77.0.2"),
                          ("sca", "10.77.0.11"), ("scb", "10.77.0.12")):
        assert f"host {host} ({address}): copy {out / 'access' / host}/ to access/" in printed
        assert (out / "access" / host / "router.json5").is_file()
    assert "python -m fsw --spacecraft 3 4 5 --scenario default.toml" in printed
    assert "--zenoh-config access/{node}.json5" in printed
    assert "python -m ground --scenario default.toml" in printed
    assert "python -m sim --scenario default.toml" in printed
    assert f"--zenoh-config {out / 'access' / 'tlm.json5'}" in printed
    sim = json.loads((out / "access" / "sim" / "router.json5").read_text())
    assert sim["connect"]["endpoints"] == ["tls/10.77.0.1:7447"]
    # the folder copied to its host as access/: the router finds its files there
    assert sim["transport"]["auth"]["usrpwd"]["dictionary_file"] == "access/users.txt"
    assert sim["transport"]["link"]["tls"] == {"listen_certificate": "access/router.pem",
                                               "listen_private_key": "access/router.key",
                                               "root_ca_certificate": "access/authority.pem"}


def test_a_hosts_folder_copied_as_access_starts_its_router(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, free_port: int) -> None:
    """The printed instructions work: the hub's folder, copied to another place as access/,
    starts its router there (its files named relative to it); here on loopback ports, as the
    map's addresses are not this machine's."""
    import shutil

    import zenoh

    out = tmp_path / "lab"
    assert main(["run", "--hosts", LAB, "--out", str(out)]) == 0
    there = tmp_path / "groundhost"
    shutil.copytree(out / "access" / "ground", there / "access")
    monkeypatch.chdir(there)
    config = json.loads((there / "access" / "router.json5").read_text())
    config["listen"]["endpoints"] = [f"tls/127.0.0.1:{free_port}"]
    router = zenoh.open(zenoh.Config.from_json5(json.dumps(config)))
    router.close()
