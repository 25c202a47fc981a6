"""Stub of ``mcsample._core.io``: see ``mcsample.io`` for the docs."""

from os import PathLike
from typing import Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

_Path = Union[str, PathLike[str]]

def read_exr(path: _Path) -> NDArray[np.float32]: ...
def write_exr(path: _Path, image: ArrayLike, half: bool = False) -> None: ...
def read_hdr(path: _Path) -> NDArray[np.float32]: ...
def write_png(path: _Path, image: ArrayLike, exposure: float = 0.0, srgb: bool = True) -> None: ...
def read_mesh(
    path: _Path,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64] | None]: ...
