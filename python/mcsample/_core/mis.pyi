"""Stub of ``mcsample._core.mis``: see ``mcsample.mis``."""

from typing import Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

_Floats = Union[NDArray[np.float64], NDArray[np.float32], np.float64, np.float32]

def balance_heuristic(pdf_a: ArrayLike, pdf_b: ArrayLike) -> _Floats: ...
def power_heuristic(pdf_a: ArrayLike, pdf_b: ArrayLike, beta: float = 2.0) -> _Floats: ...
