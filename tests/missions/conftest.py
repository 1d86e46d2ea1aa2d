"""Every test in tests/missions/ flies a whole mission or starts processes: marked ``mission``
here, by folder, so that ``python -m pytest -m "not mission"`` runs the unit tests alone and
``python -m pytest`` still runs everything."""

from __future__ import annotations

from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


@pytest.hookimpl(tryfirst=True)  # before ``-m`` deselects by marker
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if HERE in Path(item.path).parents:
            item.add_marker(pytest.mark.mission)
