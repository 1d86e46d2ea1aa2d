"""Bad input to the commands, as a table (issue 40): each case drives ``insp-fdir`` in this
process with one bad value and asserts the exit code, that the message names the problem,
that no traceback is printed, and that the output folder was not made, or that nothing in it
changed."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.cli import main
from deploy.out_folder import OutFolderError, prepare, written
from deploy.router import address_taken

REPO = Path(__file__).resolve().parents[2]
NOMINAL = REPO / "deploy" / "scenarios" / "nominal.toml"

FAULT = "[[faults]]\nspacecraft = 1\nkind = \"{kind}\"\nstart_s = {start}\n{extra}\n"
"""A fault appended to the paper's scenario (1,200 s, 5 observers)."""


def _scenario(tmp: Path, kind: str, extra: str, start: float = 100.0) -> Path:
    path = tmp / "bad.toml"
    path.write_text(NOMINAL.read_text() + "\n" + FAULT.format(kind=kind, start=start,
                                                                extra=extra))
    return path


# (id, command line after `insp-fdir`, with {scenario}/{out}, the scenario's fault or raw
#  bytes, what the message must name)
CASES = [
    ("duration negative", ["run", "--duration", "-5"], None, "duration_s"),
    ("duration zero", ["run", "--duration", "0"], None, "duration_s"),
    ("duration nan", ["run", "--duration", "nan"], None, "duration_s"),
    ("duration inf", ["run", "--duration", "inf"], None, "duration_s"),
    ("seed negative", ["run", "--seed", "-1"], None, "seed"),
    ("duration under a tick", ["run", "--duration", "1e-9"], None, "shorter than one tick"),
    ("thruster leak of a million", ["run"], ("thruster_bias", "magnitude = 1e6"),
     "thruster_bias magnitude must be in (0, 1]"),
    ("negative leak", ["run"], ("thruster_bias", "magnitude = -0.4"), "thruster_bias magnitude"),
    ("negative pointing", ["run"], ("pointing_actuator", "magnitude = -5"),
     "pointing_actuator magnitude"),
    ("negative nav bias", ["run"], ("nav_sensor_bias", "magnitude = -5"),
     "nav_sensor_bias magnitude"),
    ("negative faulty data", ["run"], ("faulty_data", "magnitude = -2"), "faulty_data magnitude"),
    ("faulty data of one", ["run"], ("faulty_data", "magnitude = 1.0"), "not 1"),
    ("link loss with a magnitude", ["run"], ("link_loss", "magnitude = 0.5"),
     "takes no magnitude"),
    ("fault after the end", ["run"], ("camera_degradation", "magnitude = 0.5", 1300.0),
     "not before the end of the run"),
    ("scenario not UTF-8", ["run"], b"name = \"x\"\n\xff\xfe\n", "not UTF-8"),
    ("endpoint in process", ["run", "--endpoint", "tcp/127.0.0.1:7500"], None,
     "--endpoint apply only to --transport zenoh"),
    ("restarts in process", ["run", "--restart-on-crash", "--audit-access"], None,
     "--restart-on-crash, --audit-access apply only"),
    ("hosting in process", ["run", "--hosting", "one-per-process", "--processes", "2"], None,
     "--processes, --hosting apply only"),
    ("no processes", ["run", "--processes", "0"], None,
     "--processes takes a count of at least 1, not 0"),
]

RUN = {"run.mcap": b"\x89MCAP0\r\nold", "summary.json": b"{}", "report.md": b"# old"}
OUT_CASES = [
    ("out holds a run", [], RUN, "already holds report.md, run.mcap, summary.json"),
    ("overwrite a folder that is no run's", ["--overwrite"], {"thesis.tex": b"%"},
     "not a run's files"),
    ("out is a file", [], None, "a file, not a folder"),
]


@pytest.mark.parametrize("argv, fault, says", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_is_refused_cleanly(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                      argv: list[str], fault: tuple | bytes | None,
                                      says: str) -> None:
    if isinstance(fault, bytes):
        scenario = tmp_path / "bad.toml"
        scenario.write_bytes(fault)
    else:
        scenario = _scenario(tmp_path, *fault) if fault else NOMINAL
    out = tmp_path / "out"
    code = main([*argv, "--scenario", str(scenario), "--out", str(out),
                 "--transport", "inproc"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert says in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("argv, held, says", [c[1:] for c in OUT_CASES],
                         ids=[c[0] for c in OUT_CASES])
def test_an_output_folder_in_use_is_left_as_it_was(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str],
        held: dict[str, bytes] | None, says: str) -> None:
    out = tmp_path / "out"
    if held is None:
        out.write_text("notes")
    else:
        out.mkdir()
        for name, data in held.items():
            (out / name).write_bytes(data)
    before = _snapshot(out)
    code = main(["run", "--scenario", str(NOMINAL), "--out", str(out), "--transport", "inproc",
                 *argv])
    err = capsys.readouterr().err
    assert code == 2 and says in err and "Traceback" not in err, err
    assert _snapshot(out) == before


def _snapshot(path: Path) -> dict[str, bytes]:
    if path.is_file():
        return {path.name: path.read_bytes()}
    return {p.name: p.read_bytes() for p in sorted(path.iterdir())}


PARSER_CASES = [
    ("mission with a slash", ["run", "--mission", "a/b"], "--mission: 'a/b': letters"),
    ("log level bogus", ["run", "--log-level", "bogus"], "--log-level: 'bogus': one of DEBUG"),
    ("endpoint garbage", ["run", "--endpoint", "garbage"],
     "--endpoint: 'garbage' is not a Zenoh endpoint"),
    ("endpoint without a port", ["run", "--endpoint", "tcp/localhost"],
     "tcp endpoint is tcp/HOST:PORT"),
    ("advertise port out of range", ["run", "--advertise", "tls/example.org:70000"],
     "port of 1-65535"),
    ("telemetry endpoint garbage", ["tlm", "--connect", "http://x"],
     "--connect: 'http://x' is not a Zenoh endpoint"),
    ("workers zero", ["campaign", "--workers", "0"], "--workers: 0: at least 1"),
    ("limit negative", ["campaign", "--limit", "-1"], "--limit: -1: at least 1"),
    ("limit zero", ["campaign", "--limit", "0"], "--limit: 0: at least 1"),
]


@pytest.mark.parametrize("argv, says", [c[1:] for c in PARSER_CASES],
                         ids=[c[0] for c in PARSER_CASES])
def test_impossible_option_values_are_refused_by_the_parser(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], says: str) -> None:
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as stop:
        main([*argv, "--out", str(out)])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and says in err and "Traceback" not in err, err
    assert not out.exists()


def test_overwrite_removes_the_old_run_wholly_and_the_default_name_is_unique(
        tmp_path: Path) -> None:
    """No file of the old run is left to mix with the new one (a second segment
    ``run-1.mcap`` included); two runs named in the same second get ``-2``."""
    out = tmp_path / "old"
    out.mkdir()
    for name in ("run.mcap", "run-1.mcap", "report.md"):
        (out / name).write_text("old")
    assert prepare(out, tmp_path / "unused", overwrite=True) == out
    assert list(out.iterdir()) == []
    default = tmp_path / "runs" / "nominal-20261205-120000"
    first = prepare(None, default, overwrite=False)
    (first / "run.mcap").write_text("x")
    assert prepare(None, default, overwrite=False) == default.with_name(default.name + "-2")
    with pytest.raises(OutFolderError, match="already holds"):
        prepare(first, default, overwrite=False)


def test_an_unreachable_cluster_is_named_within_the_stated_time(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
        free_port: int) -> None:
    import deploy.cluster

    monkeypatch.setattr(deploy.cluster, "CONNECT_TIMEOUT_S", 1.0)
    campaign = REPO / "deploy" / "campaigns" / "paper.toml"
    code = main(["campaign", "--campaign", str(campaign), "--out", str(tmp_path / "c"),
                 "--limit", "1", "--cluster", f"tcp://127.0.0.1:{free_port}"])
    err = capsys.readouterr().err
    assert code == 2 and "no Dask scheduler answered within 1 s" in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "c" / "report.md").exists()  # nothing flown, nothing reported


def test_a_router_that_did_not_start_is_named_for_what_its_log_says(tmp_path: Path) -> None:
    """The guess 'another run?' only when the router's log says its address is taken, and the
    console names only the run's files that exist (no archive when the router never came)."""
    assert address_taken("Unable to open listener tcp/127.0.0.1:1: Address already in use "
                         "(os error 98)")
    assert not address_taken("JSON error: Endpoints must be of the form <protocol>/<address>")
    (tmp_path / "summary.json").write_text("{}")
    layout = tmp_path / "run.foxglove.json"
    layout.write_text("{}")
    assert written(tmp_path, layout, report=True) == [layout, tmp_path / "summary.json"]


def test_a_busy_endpoint_is_refused_before_any_work_with_a_free_one_to_give(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import socket

    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen()
        port = held.getsockname()[1]
        assert main(["run", "--out", str(tmp_path / "run"), "--endpoint",
                     f"tcp/127.0.0.1:{port}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(
        f"error: --endpoint tcp/127.0.0.1:{port}: the address is in use (another run?): give "
        "another, e.g. --endpoint tcp/127.0.0.1:"), err
    assert not (tmp_path / "run").exists()
