"""Random values thrown at the scenario's settings (issue 40, property-based): each is either
refused with the setting's name in the message, or accepted and flown for its first ticks
without an error: no exception, and no app failing a step.  A value that validates must never
break the run."""

from __future__ import annotations

import math
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel

from deploy.inproc import run_inproc
from interfaces.contracts.scenario import Scenario, ScenarioError, validated
from tests.conftest import small_scenario

BASE = small_scenario("fuzz", duration_s=1.5, target={"pois": 200},
                      observers={"count": 2})


def _numeric_settings() -> list[tuple[str, str]]:
    """Every (section, key) of the scenario whose value is a plain number."""
    out = []
    for section, field in Scenario.model_fields.items():
        model = field.annotation
        if isinstance(model, type) and issubclass(model, BaseModel):
            for key, value in getattr(BASE, section).model_dump().items():
                if isinstance(value, int | float) and not isinstance(value, bool):
                    out.append((section, key))
    return out


SETTINGS = _numeric_settings()
VALUES = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.integers(min_value=-10**9, max_value=10**9),
    st.sampled_from([0, -1, 1e-12, 1e12, math.nan, math.inf]))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(where=st.sampled_from(SETTINGS), value=VALUES)
def test_a_value_is_refused_by_name_or_flies(where: tuple[str, str], value: Any) -> None:
    section, key = where
    data = BASE.model_dump()
    data[section][key] = value
    try:
        scenario = validated(data, "fuzz")
    except ScenarioError as e:
        assert f"{section}.{key}" in str(e) or "(top level)" in str(e), str(e)
        return
    _, executives = run_inproc(scenario.with_overrides(None, min(scenario.duration_s, 1.5)))
    assert sum(e.app_errors for e in executives.values()) == 0, f"{section}.{key} = {value}"
