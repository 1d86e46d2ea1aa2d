"""Live telemetry's text (ground/tools/tlm.py), without a network: a message summarised as its
sequence number, sim time and short ``field=value`` text, whatever the payload, and the latest
message per key as an aligned table."""

from __future__ import annotations

import math

from ground.tools.tlm import _Row, row_key, summarize, table
from interfaces.contracts.messages import FaultReport, StateEstimate


def test_a_message_is_its_seq_time_and_short_fields() -> None:
    est = StateEstimate(sender="sc1", seq=7, t_sim=12.5, spacecraft=1,
                        x=[1.23456, 0, 0, 0, 0, 0], P=[[0.0] * 6 for _ in range(6)])
    seq, t, text = summarize(est.model_dump_json().encode(), width=200)
    assert (seq, t) == (7, 12.5)
    assert text.startswith("spacecraft=1 x=[1.23,0,0,0,0,0] P=[6 items] nis=None resets=0")
    assert "sender" not in text and "t_wall" not in text
    report = FaultReport(sender="ground", t_sim=40.0, spacecraft=2, fault_class="camera",
                         metric=0.123456, window_end_s=40.0, evidence={"nis": 3.5})
    _, _, text = summarize(report.model_dump_json().encode(), width=200)
    assert "fault_class=camera" in text and "metric=0.1235" in text
    assert "evidence={1 keys}" in text


def test_a_long_summary_is_cut_to_its_width() -> None:
    _, _, text = summarize(b'{"seq": 1, "t_sim": 0.0, "note": "' + b"a" * 200 + b'"}', width=30)
    assert len(text) == 30 and text.endswith("…")


def test_any_payload_is_summarised_without_raising() -> None:
    for payload in (b"\xff\xfe", b"[1, 2]", b"not json", b""):
        seq, t, text = summarize(payload)
        assert seq == 0 and math.isnan(t) and text.startswith("<not JSON")
    seq, t, text = summarize(b'{"seq": "x", "t_sim": "y", "a": 1}')
    assert seq == 0 and math.isnan(t) and text == "a=1"


def test_the_table_is_the_latest_row_per_key_sorted_and_aligned() -> None:
    assert table({}) == "(no messages yet)"
    rows = {"insp/m/sc/2/nav/estimate": _Row("StateEstimate", 9, 4.5, 9, "x=[1]"),
            "insp/m/ground/fdir/report": _Row("FaultReport", 1, 40.0, 1, "spacecraft=2")}
    lines = table(rows).splitlines()
    assert lines[0].split() == ["key", "type", "seq", "t_sim", "(s)", "count", "fields"]
    assert set(lines[1]) == {"-"} and len(lines[1]) == len(lines[0])
    assert [ln.split()[0] for ln in lines[2:]] == sorted(rows)
    assert lines[2].split()[1:] == ["FaultReport", "1", "40.0", "1", "spacecraft=2"]
    assert lines[2].index("FaultReport") == lines[3].index("StateEstimate")


def test_each_observer_keeps_its_row_on_a_key_the_observers_share() -> None:
    """The ground's FDIR windows of every observer share one key: each observer keeps its own
    row; a key of one observer (its ``/sc/<n>/``) and a message about none keep the key."""
    from interfaces.contracts.messages import FdirWindow

    key = "insp/m/ground/fdir/window"
    rows = {}
    for sc in (1, 2, 3, 2):
        w = FdirWindow(sender="ground", t_sim=30.0, spacecraft=sc, t_start_s=0.0,
                       t_end_s=30.0, images=10)
        row = row_key(key, w.model_dump_json().encode())
        rows[row] = _Row("FdirWindow", 0, 30.0, rows[row].count + 1 if row in rows else 1, "")
    assert sorted(rows) == [f"{key} [sc1]", f"{key} [sc2]", f"{key} [sc3]"]
    assert rows[f"{key} [sc2]"].count == 2
    assert [ln.split()[1] for ln in table(rows).splitlines()[2:]] == ["[sc1]", "[sc2]", "[sc3]"]
    own = "insp/m/sc/2/nav/estimate"
    assert row_key(own, b'{"spacecraft": 2}') == own
    assert row_key("insp/m/sim/tick", b'{"t_sim": 1.0}') == "insp/m/sim/tick"
    assert row_key(key, b"not json") == key
