"""The packed POI sets and precisions (interfaces/contracts/messages/poi_packing.py): exact to
the bit whatever the values, compact for the camera's, and refused when malformed."""

from __future__ import annotations

import json

import numpy as np
import pytest
from pydantic import ValidationError

from interfaces.contracts.messages import CameraImage, PoiObservations
from interfaces.contracts.messages.poi_packing import (
    pack_poi,
    pack_precision,
    quantise,
    unpack_poi,
    unpack_precision,
)


def _bits(values: np.ndarray) -> list[int]:
    return np.asarray(values, dtype=np.float64).view(np.int64).tolist()


def test_quantised_precisions_come_back_bit_for_bit_as_decimals() -> None:
    """Every decade the camera can measure, and the values that round up to a new decade."""
    rng = np.random.default_rng(11)
    for decade in range(-12, 12):
        values = quantise(10.0 ** decade * rng.uniform(1.0, 10.0, 5000))
        values[:3] = quantise(10.0 ** decade * np.array([0.9999996, 9.9999996, 1.0]))
        packed = pack_precision(values)
        assert packed.startswith("dec:"), decade
        assert _bits(unpack_precision(packed)) == _bits(values)


def test_any_other_floats_come_back_bit_for_bit_as_doubles() -> None:
    rng = np.random.default_rng(12)
    values = np.concatenate([rng.uniform(0.0, 1.0, 1000), [0.0, 5e-324, 1e-300, 1e12],
                             rng.standard_normal(100) * 1e-20])
    packed = pack_precision(values)
    assert packed.startswith("f64:")
    assert _bits(unpack_precision(packed)) == _bits(values)
    assert pack_precision([-0.0]).startswith("f64:")  # -0.0 is not the decimal 0
    assert pack_precision([0.0, 0.25]).startswith("dec:")


def test_poi_sets_come_back_whatever_their_order() -> None:
    rng = np.random.default_rng(13)
    ascending = np.sort(rng.choice(200_000, 3000, replace=False))
    cases = {"d16": [ascending, [], [0], [65_535], [3, 3, 4], [65_535, 131_070]],
             "i64": [[65_536], [0, 65_536], [9, 2, 5], [-4, 1], [2**40]]}
    for codec, sets in cases.items():
        for poi in sets:
            packed = pack_poi(poi)
            assert packed.startswith(codec + ":"), poi
            assert unpack_poi(packed).tolist() == list(np.asarray(poi, dtype=np.int64))


def test_a_camera_image_is_under_half_its_json_lists() -> None:
    """The size the store and the archive count: 1,100 POIs of a 5,000-POI target."""
    rng = np.random.default_rng(14)
    poi = np.sort(rng.choice(5000, 1100, replace=False))
    prec = quantise(1.0 / (np.pi * rng.uniform(20.0, 30.0, 1100) ** 2)
                    * (1.0 + 0.05 * rng.standard_normal(1100)))
    image = CameraImage.of_arrays("sim", 1.0, 1, poi, prec)
    lists = json.dumps({"poi": poi.tolist(), "precision": prec.tolist()})
    assert len(image.model_dump_json()) < len(lists) / 2


def test_lists_of_old_archives_and_arrays_build_the_same_message() -> None:
    """``poi=``/``precision=`` as lists (an archive written before the packing) or arrays give
    the message the packed strings give, and it reads back as JSON."""
    lists = {"sender": "sc1", "t_sim": 2.0, "spacecraft": 1, "image_t_s": 2.0,
             "poi": [4, 8, 15], "precision": [0.5, 0.001, 2.0]}
    old = PoiObservations.model_validate_json(json.dumps(lists))
    arrays = PoiObservations(**(lists | {"poi": np.array([4, 8, 15]),
                                         "precision": np.array([0.5, 0.001, 2.0])}))
    assert old == arrays == PoiObservations.model_validate_json(old.model_dump_json())
    assert old.poi.tolist() == [4, 8, 15] and old.precision.tolist() == [0.5, 0.001, 2.0]


@pytest.mark.parametrize("fields", [
    {"poi_packed": "d16:AQA=", "precision_packed": "dec:"},  # 1 POI, 0 precisions
    {"poi_packed": "d16:AQ==", "precision_packed": "dec:"},  # half a step
    {"poi_packed": "AQA=", "precision_packed": "dec:"},  # no codec
    {"poi_packed": "x16:AQA=", "precision_packed": "dec:AAAAAA=="},  # unknown codec
    {"poi_packed": "d16:A!A=", "precision_packed": "dec:"},  # not base64
    {"poi_packed": "i64:" + "/" * 10 + "w==", "precision_packed": "f64:" + "A" * 11 + "="},
    {"poi_packed": pack_poi([1]), "precision_packed": pack_precision([np.nan])},
    {"poi_packed": pack_poi([1]), "precision_packed": pack_precision([np.inf])},
    {"poi_packed": pack_poi([1]), "precision_packed": pack_precision([-1.0])},
    {"poi_packed": pack_poi([1]), "precision_packed": pack_precision([2e12])},
    {"poi_packed": pack_poi([-1]), "precision_packed": pack_precision([1.0])},
    {"poi": [1, 2], "precision": [0.1]},
    {"poi": ["1"], "precision": [0.1]},
    {"poi": [True], "precision": [0.1]},
    {"poi": [1.5], "precision": [0.1]},
    {"poi": [[1]], "precision": [[0.1]]},
    {"poi": [1], "precision": [float("nan")]},
    {"poi": [1], "precision": ["0.1"]},
])
def test_malformed_packed_lists_are_refused(fields: dict[str, object]) -> None:
    with pytest.raises(ValidationError):
        CameraImage(sender="sim", t_sim=1.0, spacecraft=1, **fields)  # type: ignore[arg-type]


def test_hostile_json_is_refused_with_a_clear_error() -> None:
    text = json.dumps({"sender": "sim", "t_sim": 1.0, "spacecraft": 1,
                       "poi_packed": "dec:AAAA", "precision_packed": "d16:AQA="})
    with pytest.raises(ValidationError, match="unknown POI codec 'dec'"):
        CameraImage.model_validate_json(text)
