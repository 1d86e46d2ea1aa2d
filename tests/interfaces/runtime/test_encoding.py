"""Message bytes (interfaces/runtime/encoding.py): the JSON pydantic writes, for floats,
strings and what orjson cannot write, and for camera images of arrays (every message type of a
run: tests/missions/test_encoding_run.py)."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from interfaces.contracts.messages import CameraImage, Message, PoiObservations, SimStatus
from interfaces.contracts.messages.poi_packing import pack_poi, unpack_poi
from interfaces.runtime.encoding import encode


def _pydantic(msg: Message) -> bytes:
    return msg.model_dump_json().encode()


class _Numbers(Message):
    """A message of free-form numbers (floats across the whole exponent range, big ints)."""

    items: list[int]
    values: list[float]


def test_floats_strings_and_fallback() -> None:
    rng = np.random.default_rng(5)
    values = [0.0, -0.0, 5e-324, 1.7976931348623157e308, 1e15, 1e16, 1e21, 1e22, 1e-5, 1e-7,
              0.1, 1.0 / 3.0, 123456789012345678.0]
    values += (rng.standard_normal(20_000) * 10.0 ** rng.uniform(-300, 300, 20_000)).tolist()
    numbers = _Numbers.model_construct(sender="sim", seq=1, t_sim=1.0, t_wall=0.0,
                                       items=list(range(len(values))), values=values)
    assert encode(numbers) == _pydantic(numbers)
    text = "".join(chr(i) for i in range(300)) + "é漢字\u2028\u2029😀\x7f"
    status = SimStatus(sender="sim", t_sim=0.0, state="aborted", k=0, reason=text)
    assert encode(status) == _pydantic(status)
    huge = _Numbers.model_construct(sender="sim", seq=1, t_sim=1.0, t_wall=0.0,
                                    items=[2**70], values=[1.0])  # beyond orjson's ints
    assert encode(huge) == _pydantic(huge)


def test_observations_of_an_image_are_the_validated_message() -> None:
    """The camera app shares an image's validated lists without validating them again: the
    same message, the same bytes; a time outside the schema is still refused."""
    image = CameraImage(sender="sim", t_sim=3.0, spacecraft=2, poi=[1, 5, 9],
                        precision=[0.5, 1e-3, 2.0])
    shared = PoiObservations.of_image(image, "sc2", 3.0)
    checked = PoiObservations(sender="sc2", t_sim=3.0, spacecraft=2, image_t_s=3.0,
                              poi=[1, 5, 9], precision=[0.5, 1e-3, 2.0])
    assert shared == checked and encode(shared) == encode(checked) == _pydantic(checked)
    assert shared.arrays()[0].tolist() == [1, 5, 9]
    with pytest.raises(ValidationError, match="t_sim"):
        PoiObservations.of_image(image, "sc2", float("nan"))


def test_an_image_of_arrays_keeps_them_for_its_subscribers() -> None:
    """The sim's image keeps copies of its arrays (equal to its packed lists, read-only), and
    the observations shared from it carry the same arrays; a copy with other packed lists
    unpacks its own."""
    poi, precision = np.array([1, 5, 9]), np.array([0.5, 1e-3, 2.0])
    image = CameraImage.of_arrays("sim", 3.0, 2, poi, precision)
    poi[0] = 7  # the caller's array may change afterwards
    idx, prec = image.arrays()
    assert idx.tolist() == [1, 5, 9] and prec.tolist() == [0.5, 1e-3, 2.0]
    assert image.poi is idx and image.precision is prec
    assert unpack_poi(image.poi_packed).tolist() == [1, 5, 9]
    assert not idx.flags.writeable and not prec.flags.writeable
    shared = PoiObservations.of_image(image, "sc2", 3.0)
    assert shared.arrays()[0] is idx and shared.arrays()[1] is prec
    other = image.model_copy(update={"poi_packed": pack_poi([2, 3, 4])})
    assert other.arrays()[0].tolist() == [2, 3, 4] and other.arrays()[1].tolist() == prec.tolist()


def test_an_image_of_arrays_is_checked_as_pydantic_would() -> None:
    """The sim's image checks its arrays with numpy; it equals the message pydantic validates,
    and what pydantic refuses is refused (by pydantic: the fast path passes it on)."""
    rng = np.random.default_rng(3)
    poi = np.sort(rng.choice(5000, 2500, replace=False))
    precision = rng.uniform(0.0, 50.0, 2500)
    fast = CameraImage.of_arrays("sim", 12.5, 3, poi, precision)
    checked = CameraImage(sender="sim", t_sim=12.5, spacecraft=3, poi=poi.tolist(),
                          precision=precision.tolist())
    assert fast.model_dump() == checked.model_dump() and encode(fast) == _pydantic(checked)
    assert fast.poi.dtype == np.int64 and fast.precision.dtype == np.float64
    bad_precision = [np.nan, -1.0, 2e12, np.inf]
    for value in bad_precision:
        p = precision.copy()
        p[7] = value
        with pytest.raises(ValidationError):
            CameraImage.of_arrays("sim", 12.5, 3, poi, p)
    with pytest.raises(ValidationError):
        CameraImage.of_arrays("sim", 12.5, 3, np.r_[-1, poi[1:]], precision)
    with pytest.raises(ValidationError):
        CameraImage.of_arrays("sim", 12.5, 3, poi[:-1], precision)
    with pytest.raises(ValidationError):
        CameraImage.of_arrays("sim", 12.5, 0, poi, precision)
    with pytest.raises(ValidationError):
        CameraImage.of_arrays("sim", -1.0, 3, poi, precision)
