"""The flight software process's command line (fsw/__main__.py): several spacecraft may share
a process, each with an account of its own; what cannot be hosted is refused before any
session opens."""

from __future__ import annotations

import pytest

from fsw.__main__ import main


@pytest.mark.parametrize(("argv", "says"), [
    (["--spacecraft", "1", "1"], "names a spacecraft twice"),
    (["--spacecraft", "1", "2", "--zenoh-config", "access/sc1.json5"],
     "put '{node}' in --zenoh-config"),
    (["--spacecraft"], "expected at least one argument"),
    (["--spacecraft", "x"], "invalid int value"),
])
def test_spacecraft_that_cannot_share_the_process_are_refused(
        argv: list[str], says: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as ended:
        main([*argv, "--scenario", "deploy/scenarios/default.toml"])
    assert ended.value.code == 2 and says in capsys.readouterr().err
