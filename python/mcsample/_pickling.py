"""Unpickling of mcsample's compiled objects (``mcsample._core``): their
``__reduce__`` names a class, a constructor method of it (or None for the
class itself), arguments and keyword arguments, and this makes the object
again."""

from __future__ import annotations

from typing import Any


def rebuild(cls: type, method: str | None, args: tuple[Any, ...],
            kwargs: dict[str, Any]) -> Any:
    """``cls(*args, **kwargs)``, or ``getattr(cls, method)(*args, **kwargs)``."""
    make = cls if method is None else getattr(cls, method)
    return make(*args, **kwargs)
