"""Seeded random streams: one ``numpy.random.Generator`` per (seed, stream name, index)."""

from __future__ import annotations

import zlib

import numpy as np


def stream(seed: int, name: str, index: int = 0) -> np.random.Generator:
    """Independent generator for a named stream; adding a stream or an index never shifts the
    random numbers of another (determinism across configurations)."""
    return np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(name.encode()), index]))
