"""A run's disk space (deploy/disk_space.py): the reserve holds what it asks, or as much as a
fuller disk has, and gives it all back; the check refuses a disk too small with the figures;
a full disk is recognised through the causes of an error."""

from __future__ import annotations

import errno
from pathlib import Path

import pytest

from deploy.disk_space import (
    DiskSpaceError,
    Reserve,
    check_space,
    estimate_archive_bytes,
    free_bytes,
    is_disk_full,
)
from tests.conftest import small_scenario
from tests.mounts import tmpfs


@pytest.mark.parametrize("ask_mb, holds_mb", [(2.0, 2.0), (8.0, 4.0)])
def test_a_reserve_holds_what_the_disk_has_and_gives_it_back(tmp_path: Path, ask_mb: float,
                                                             holds_mb: float) -> None:
    with tmpfs(tmp_path / "disk", 4.0) as disk:
        free = free_bytes(disk)
        with Reserve(disk, int(ask_mb * 1e6)) as reserve:
            held = free - free_bytes(disk)
            assert held == pytest.approx(min(holds_mb * 1e6, free), rel=0.05)
            assert reserve.path.exists()
        assert free_bytes(disk) == free and not reserve.path.exists()


def test_a_disk_too_small_for_the_run_is_refused_with_the_figures(tmp_path: Path) -> None:
    scenario = small_scenario("disk", duration_s=3000.0, target={"pois": 5000},
                              rates={"high_hz": 10.0})
    with tmpfs(tmp_path / "disk", 10.0) as disk:
        with pytest.raises(DiskSpaceError) as refused:
            check_space(disk / "run", scenario)
        need = estimate_archive_bytes(scenario)
        assert need > 10e6 and refused.value.errno == errno.ENOSPC
        assert f"--out {disk / 'run'} has " in refused.value.strerror
        assert "3 observers for 3000 s" in refused.value.strerror
        assert check_space(disk / "run", scenario.model_copy(update={"duration_s": 10.0})) > 0


def test_a_full_disk_is_found_among_the_causes() -> None:
    try:
        try:
            raise OSError(errno.ENOSPC, "No space left on device")
        except OSError as e:
            raise RuntimeError("writing the archive") from e
    except RuntimeError as wrapped:
        assert is_disk_full(wrapped)
    assert not is_disk_full(OSError(errno.EACCES, "Permission denied"))
