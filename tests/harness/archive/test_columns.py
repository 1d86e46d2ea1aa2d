"""One message as one flat row (harness/archive/columns.py), on constructed messages: the columns
come from the model's declared types -- fixed-length lists one column per element, nested
models and dicts dotted names, lists of varying length whole -- so a topic has the same columns
whatever the values, an optional part left out included."""

from __future__ import annotations

import numpy as np

from harness.archive.columns import Fields, Fixed, Keyed, Leaf, RowFlattener, model_shape
from interfaces.contracts.messages import (
    AttitudeMeasurement,
    ExecStats,
    FaultReport,
    GroupStats,
    PoiObservations,
    StateEstimate,
    TruthState,
)

HEADER = ["sender", "seq", "t_sim", "t_wall"]


def _estimate() -> StateEstimate:
    return StateEstimate(sender="sc1", seq=4, t_sim=2.5, spacecraft=1,
                         x=[1.0, 2.0, 3.0, 0.1, 0.2, 0.3], P=(np.eye(6) * 0.5).tolist(), nis=1.2)


def test_fixed_vectors_and_matrices_get_one_column_per_element() -> None:
    row = RowFlattener().row(_estimate())
    assert list(row) == [*HEADER, "spacecraft", *(f"x.{i}" for i in range(6)),
                         *(f"P.{i}.{j}" for i in range(6) for j in range(6)), "nis", "resets"]
    assert [row[f"x.{i}"] for i in range(6)] == [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]
    assert row["P.2.2"] == 0.5 and row["P.2.3"] == 0.0
    assert (row["sender"], row["seq"], row["t_sim"], row["nis"]) == ("sc1", 4, 2.5, 1.2)


def test_the_shape_is_the_models_not_the_values() -> None:
    shape = model_shape(StateEstimate)
    assert isinstance(shape, Fields)
    fields = dict(shape.fields)
    assert fields["x"] == Fixed(6, Leaf()) and fields["P"] == Fixed(6, Fixed(6, Leaf()))
    assert fields["nis"] == Leaf()
    flat = RowFlattener()
    assert list(flat.row(_estimate())) == list(flat.row(_estimate().model_copy(
        update={"nis": None})))


def test_an_optional_fixed_list_left_out_keeps_its_columns_as_none() -> None:
    flat = RowFlattener()
    fix = AttitudeMeasurement(sender="sim", t_sim=1.0, spacecraft=2, gyro_radps=[0.1, 0.0, 0.0],
                              star_tracker=[0.0, 0.0, 0.0, 1.0], st_sigma_cross_rad=5e-5,
                              st_sigma_roll_rad=3e-4)
    none = AttitudeMeasurement(sender="sim", t_sim=1.1, spacecraft=2, gyro_radps=[0.1, 0.0, 0.0])
    with_fix, without = flat.row(fix), flat.row(none)
    assert list(with_fix) == list(without)
    assert [with_fix[f"star_tracker.{i}"] for i in range(4)] == [0.0, 0.0, 0.0, 1.0]
    assert [without[f"star_tracker.{i}"] for i in range(4)] == [None] * 4


def test_nested_models_and_dicts_get_dotted_names() -> None:
    flat = RowFlattener()
    stats = ExecStats(sender="sc1", t_sim=3.0, node="sc1",
                      groups={"high": GroupStats(runs=30, max_exec_ms=1.5), "low": GroupStats()})
    row = flat.row(stats)
    assert row["groups.high.runs"] == 30 and row["groups.high.max_exec_ms"] == 1.5
    assert row["groups.low.runs"] == 0 and "groups" not in row
    assert dict(model_shape(ExecStats).fields)["groups"] == Keyed(model_shape(GroupStats))
    report = FaultReport(sender="ground", t_sim=40.0, spacecraft=2, fault_class="camera",
                         window_end_s=40.0, evidence={"nis": 3.5, "beta": 0.98})
    row = flat.row(report)
    assert (row["evidence.nis"], row["evidence.beta"]) == (3.5, 0.98)
    assert not any(k.startswith("evidence") for k in flat.row(report.model_copy(
        update={"evidence": {}})))  # a dict's columns are its keys


def test_lists_of_varying_length_stay_whole() -> None:
    truth = TruthState(sender="sim", t_sim=1.0, spacecraft=[1, 2],
                       r_lvlh_m=[[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
                       v_lvlh_mps=[[0.0, 0.0, 0.0], [0.0, 0.0, 0.1]])
    row = RowFlattener().row(truth)
    assert row["spacecraft"] == [1, 2]
    assert row["r_lvlh_m"] == [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]]
    assert not any(k.startswith("r_lvlh_m.") for k in row)


def test_packed_poi_sets_and_precisions_are_their_lists_in_place() -> None:
    obs = PoiObservations(sender="sc2", seq=3, t_sim=4.0, spacecraft=2, image_t_s=3.5,
                          poi=[7, 9, 400], precision=[0.25, 1e-3, 3.0])
    row = RowFlattener().row(obs)
    assert list(row)[:8] == [*HEADER, "spacecraft", "poi", "precision", "image_t_s"]
    assert row["poi"] == [7, 9, 400] and row["precision"] == [0.25, 1e-3, 3.0]
    assert type(row["poi"][0]) is int and type(row["precision"][0]) is float
