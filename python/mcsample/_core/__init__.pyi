"""Type stub of mcsample's compiled core (``mcsample._core``)."""

from typing import Any, Sequence, Union, final

import numpy as np
from numpy.typing import ArrayLike, DTypeLike, NDArray

from . import io as io
from . import warp as warp

__version__: str

_Shape = Union[None, int, Sequence[int]]

@final
class Rng:
    """PCG32 (O'Neill's pcg32_random_r), seeded as pcg32_srandom_r(seed, stream)."""

    def __new__(cls, seed: int | None = None, stream: int | None = None) -> Rng: ...
    def random(self, shape: _Shape = None, dtype: DTypeLike | None = None) -> Any:
        """Uniform floats in [0, 1) of ``shape`` (a numpy scalar for None)."""
    def next_uint32(self, shape: _Shape = None) -> Any:
        """Raw 32-bit outputs of ``shape`` (uint32)."""
    def advance(self, n: int) -> None:
        """Skips ``n`` outputs in O(log n)."""
    @property
    def seed(self) -> int: ...
    @property
    def stream(self) -> int: ...
    def copy(self) -> Rng: ...
    def __copy__(self) -> Rng: ...
    def __deepcopy__(self, memo: Any) -> Rng: ...

def uniform(n: int, dim: int | None = None, seed: int | None = None,
            dtype: DTypeLike | None = None) -> NDArray[np.floating[Any]]:
    """(n, dim) uniform floats in [0, 1): the first n*dim numbers of Rng(seed)."""

def set_num_threads(n: int) -> None:
    """Threads for batch calls, 1 to 1024."""

def get_num_threads() -> int:
    """Threads batch calls use."""

def _trigger_panic() -> None: ...
