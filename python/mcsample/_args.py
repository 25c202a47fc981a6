"""Argument checks shared by the Python modules (the compiled core checks
its own)."""

from __future__ import annotations

import operator


def integer(value: object, arg: str, minimum: int = 0) -> int:
    """``value`` as an int of at least ``minimum``; TypeError for a
    non-integer, ValueError below ``minimum``, each naming ``arg``."""
    try:
        n = operator.index(value)  # type: ignore[arg-type]
    except TypeError:
        raise TypeError(f"{arg} must be an integer, got {type(value).__name__}") from None
    if n < minimum:
        raise ValueError(f"{arg} = {n}: must be >= {minimum}")
    return n
