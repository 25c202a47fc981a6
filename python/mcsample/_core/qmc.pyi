"""Stub of ``mcsample._core.qmc``: see ``mcsample.qmc`` for the engines."""

from typing import Any, Literal, final

import numpy as np
from numpy.typing import DTypeLike, NDArray

@final
class SobolPoints:
    """Sobol' points (Joe and Kuo's direction numbers, scipy's order)."""

    def __new__(
        cls,
        d: int,
        scramble: Literal["none", "owen", "lms"] = "owen",
        seed: int | None | np.random.Generator = 0,
    ) -> SobolPoints: ...
    def points(self, first: int, n: int, dtype: DTypeLike | None = None) -> NDArray[Any]:
        """Points ``first .. first + n - 1``, shape (n, d)."""
    @property
    def d(self) -> int: ...

@final
class HaltonPoints:
    """Halton points, plain or with random digit permutations."""

    def __new__(
        cls, d: int, scramble: bool = True, seed: int | None | np.random.Generator = 0
    ) -> HaltonPoints: ...
    def points(self, first: int, n: int, dtype: DTypeLike | None = None) -> NDArray[Any]:
        """Points ``first .. first + n - 1``, shape (n, d)."""
    @property
    def d(self) -> int: ...

@final
class PatternPoints:
    """Stratified patterns of n points drawn whole."""

    def __new__(
        cls,
        kind: Literal["lhs", "lhs-centered", "stratified", "multijitter"],
        d: int,
        seed: int | None | np.random.Generator = 0,
    ) -> PatternPoints: ...
    def points(self, number: int, n: int, dtype: DTypeLike | None = None) -> NDArray[Any]:
        """The pattern numbered ``number``, of ``n`` points, shape (n, d)."""
    @property
    def d(self) -> int: ...
