"""Stub of ``mcsample._core.qmc``: see ``mcsample.qmc`` for the engines."""

from typing import Any, Literal, final

import numpy as np
from numpy.typing import DTypeLike, NDArray

@final
class Points:
    """Quasi-random points and stratified patterns, filled from any index."""

    def __new__(
        cls,
        kind: Literal[
            "sobol",
            "sobol-owen",
            "sobol-lms",
            "halton",
            "halton-permuted",
            "lhs",
            "lhs-centered",
            "stratified",
            "multijitter",
        ],
        d: int,
        seed: int | None | np.random.Generator = 0,
    ) -> Points: ...
    def points(self, start: int, n: int, dtype: DTypeLike | None = None) -> NDArray[Any]:
        """``n`` points from ``start`` (a sequence's index, a pattern's number),
        shape (n, d)."""
    @property
    def d(self) -> int: ...
