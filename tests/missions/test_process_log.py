"""A supervised process's log as the launcher quotes it (deploy/processes.py): its last lines,
without the terminal colour codes Zenoh's logger writes, so none reach summary.json or
report.md."""

from __future__ import annotations

from pathlib import Path

from deploy.processes import Child


def test_a_log_tail_has_no_colour_codes(tmp_path: Path) -> None:
    log = tmp_path / "router.log"
    log.write_text("first\n" + "\x1b[2m2026-12-07T12:00:00Z\x1b[0m \x1b[31mERROR\x1b[0m "
                   "\x1b[1;33mzenoh::net\x1b[0m Unable to open listener\nlast\n")
    tail = Child("router", [], log).log_tail(2)
    assert tail == "2026-12-07T12:00:00Z ERROR zenoh::net Unable to open listener\nlast"
