"""Stub of ``mcsample._core.mis``: see ``mcsample.mis``."""

from typing import Any

from numpy.typing import ArrayLike

def balance_heuristic(pdf_a: ArrayLike, pdf_b: ArrayLike) -> Any: ...
def power_heuristic(pdf_a: ArrayLike, pdf_b: ArrayLike, beta: float = 2.0) -> Any: ...
