"""Seeds, one meaning everywhere mcsample takes one: an int in [0, 2⁶⁴) is
used as it is (the same seed gives the same bits on any thread count);
None draws a fresh seed from the operating system, as numpy does; a
``numpy.random.Generator`` draws one from itself (so a seeded Generator
gives reproducible results)."""

from __future__ import annotations

import operator
import secrets
from typing import Union

import numpy as np

__all__ = ["SeedLike", "resolve_seed"]

SeedLike = Union[int, None, np.random.Generator]


def resolve_seed(seed: SeedLike, arg: str = "seed") -> int:
    """The 64-bit seed that ``seed`` stands for (see the module doc).

    Raises TypeError for anything else, ValueError for an int outside
    [0, 2⁶⁴)."""
    if seed is None:
        return secrets.randbits(64)
    if isinstance(seed, np.random.Generator):
        return int(seed.integers(0, 2**64, dtype=np.uint64))
    try:
        value = operator.index(seed)
    except TypeError:
        raise TypeError(f"{arg} must be an integer, None or a numpy.random.Generator, "
                        f"got {type(seed).__name__}") from None
    if not 0 <= value < 2**64:
        raise ValueError(f"{arg} = {value}: must be an integer from 0 to {2**64 - 1}")
    return value
