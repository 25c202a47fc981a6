"""Type stub of mcsample's compiled core (``mcsample._core``)."""

import os
from typing import Any, Final, Iterator, Literal, Sequence, Union, final

import numpy as np
from numpy.typing import ArrayLike, DTypeLike, NDArray

from . import estimators as estimators
from . import io as io
from . import mis as mis
from . import qmc as qmc
from . import render as render
from . import warp as warp

__version__: str

_Shape = Union[None, int, Sequence[int]]
#: Arrays in the input's precision (float32 or float64), or one such
#: scalar for an unbatched input.
_Floats = Union[NDArray[np.float64], NDArray[np.float32], np.float64, np.float32]
#: int64 indices, an array or one scalar.
_Ints = Union[NDArray[np.int64], np.int64]
_Mapping = Literal["latlong", "angular", "cube"]
_Sampling = Literal["luminance", "piecewise", "mitsuba"]

@final
class Rng:
    """PCG32 (O'Neill's pcg32_random_r), seeded as pcg32_srandom_r(seed, stream)."""

    def __new__(cls, seed: int | np.random.Generator | None = 0,
                stream: int | None = 0) -> Rng: ...
    def random(self, shape: _Shape = None, dtype: DTypeLike | None = None) -> _Floats:
        """Uniform floats in [0, 1) of ``shape`` (a numpy scalar for None)."""
    def next_uint32(self, shape: _Shape = None) -> NDArray[np.uint32] | np.uint32:
        """Raw 32-bit outputs of ``shape`` (uint32)."""
    def advance(self, n: int) -> None:
        """Skips ``n`` outputs in O(log n)."""
    seed: Final[int]
    stream: Final[int]
    def copy(self) -> Rng: ...
    def __copy__(self) -> Rng: ...
    def __deepcopy__(self, memo: Any) -> Rng: ...

def uniform(n: int, dim: int | None = 2, seed: int | np.random.Generator | None = 0,
            dtype: DTypeLike | None = None) -> NDArray[np.floating[Any]]:
    """(n, dim) uniform floats in [0, 1): the first n*dim numbers of Rng(seed)."""

def set_num_threads(n: int) -> None:
    """Threads for batch calls, 1 to 1024."""

def get_num_threads() -> int:
    """Threads batch calls use."""

def _trigger_panic() -> None: ...

class _Record:
    def __len__(self) -> int: ...
    def __getitem__(self, key: int, /) -> Any: ...
    def __iter__(self) -> Iterator[Any]: ...
    def __bool__(self) -> bool: ...

@final
class PiecewiseSample(_Record):
    """Draws of a piecewise-constant density; unpacks as (x, pdf)."""

    x: Final[_Floats]
    pdf: Final[_Floats]

@final
class ReusedSample(_Record):
    """Draws of Discrete1D / Discrete2D.sample_reuse; unpacks as (index, u)."""

    index: Final[_Ints]
    u: Final[_Floats]

@final
class Discrete1D:
    """Discrete distribution over 0..n-1 proportional to weights (CDF inversion)."""

    def __new__(cls, weights: ArrayLike) -> Discrete1D: ...
    def sample(self, u: ArrayLike, *, out: NDArray[Any] | None = None) -> _Ints:
        """Indices (N,) int64 for u (N,) in [0, 1]."""
    def sample_reuse(self, u: ArrayLike, *, out: tuple[NDArray[Any], NDArray[Any]] | None = None) -> ReusedSample:
        """Indices and u rescaled to [0, 1) within the chosen entry."""
    def pmf(self, i: ArrayLike | None = None, *, out: NDArray[Any] | None = None) -> _Floats:
        """w[i] / sum (all entries when i is None)."""
    cdf: Final[NDArray[np.float64]]
    sum: Final[float]
    def __len__(self) -> int: ...

@final
class AliasTable:
    """Walker's alias table: O(1) sampling of 0..n-1 proportional to weights."""

    def __new__(cls, weights: ArrayLike) -> AliasTable: ...
    def sample(self, u: ArrayLike, *, out: NDArray[Any] | None = None) -> _Ints: ...
    def pmf(self, i: ArrayLike | None = None, *, out: NDArray[Any] | None = None) -> _Floats: ...
    sum: Final[float]
    def __len__(self) -> int: ...

@final
class Discrete2D:
    """Discrete distribution over the cells (row, col) of a table."""

    def __new__(cls, weights: ArrayLike) -> Discrete2D: ...
    def sample(self, u: ArrayLike, *, out: NDArray[Any] | None = None) -> _Ints:
        """(N, 2) int64 (row, col): the row by u[:, 1], the column by u[:, 0]."""
    def sample_reuse(self, u: ArrayLike, *, out: tuple[NDArray[Any], NDArray[Any]] | None = None) -> ReusedSample: ...
    def pmf(self, idx: ArrayLike | None = None, *, out: NDArray[Any] | None = None) -> _Floats: ...
    shape: Final[tuple[int, int]]
    sum: Final[float]

@final
class PiecewiseConstant1D:
    """Piecewise-constant density on [a, b] (per unit length)."""

    def __new__(cls, values: ArrayLike, *, a: float = 0.0, b: float = 1.0) -> PiecewiseConstant1D: ...
    def sample(self, u: ArrayLike, *, out: tuple[NDArray[Any], NDArray[Any]] | None = None) -> PiecewiseSample:
        """Points x and their densities pdf; unpacks as (x, pdf)."""
    def pdf(self, x: ArrayLike, *, out: NDArray[Any] | None = None) -> _Floats: ...
    def cdf(self, x: ArrayLike, *, out: NDArray[Any] | None = None) -> _Floats: ...
    def invert(self, x: ArrayLike, *, out: NDArray[Any] | None = None) -> _Floats: ...
    domain: Final[tuple[float, float]]
    integral: Final[float]
    def __len__(self) -> int: ...

@final
class PiecewiseConstant2D:
    """Piecewise-constant density on a rectangle (per unit area)."""

    def __new__(cls, values: ArrayLike, *,
                domain: tuple[tuple[float, float], tuple[float, float]] = ...,
                ) -> PiecewiseConstant2D: ...
    def sample(self, u: ArrayLike, *, out: tuple[NDArray[Any], NDArray[Any]] | None = None) -> PiecewiseSample:
        """Points x (N, 2) and pdf (N,); unpacks as (x, pdf)."""
    def pdf(self, xy: ArrayLike, *, out: NDArray[Any] | None = None) -> _Floats: ...
    def invert(self, xy: ArrayLike, *, out: NDArray[Any] | None = None) -> _Floats: ...
    domain: Final[tuple[tuple[float, float], tuple[float, float]]]
    shape: Final[tuple[int, int]]
    integral: Final[float]

@final
class Frame:
    """Orthonormal frame(s) (s, t, n) around one normal (3,) or N normals (N, 3)."""

    def __new__(cls, normal: ArrayLike) -> Frame: ...
    def to_local(self, v: ArrayLike) -> _Floats: ...
    def to_world(self, v: ArrayLike) -> _Floats: ...
    s: Final[_Floats]
    t: Final[_Floats]
    n: Final[_Floats]
    def __len__(self) -> int: ...

@final
class PhongSample(_Record):
    """Samples of Phong.sample."""

    wo: Final[_Floats]
    pdf: Final[_Floats]
    weight: Final[_Floats]
    component: Final[_Ints]

@final
class Phong:
    """Energy-normalised modified Phong BRDF (local frame, normal +z)."""

    def __new__(cls, diffuse: float | Sequence[float], specular: float | Sequence[float],
                exponent: float, *, selection: Literal["max", "luminance"] = "max") -> Phong: ...
    def eval(self, wi: ArrayLike, wo: ArrayLike) -> _Floats:
        """f_r(wi, wo) per RGB channel, (N, 3)."""
    def pdf(self, wi: ArrayLike, wo: ArrayLike) -> _Floats:
        """Density of sample per steradian, (N,)."""
    def sample(self, wi: ArrayLike, u: ArrayLike) -> PhongSample: ...
    diffuse_probability: Final[float]
    diffuse: Final[list[float]]
    specular: Final[list[float]]
    exponent: Final[float]

@final
class EnvSample(_Record):
    """Samples of EnvMap.sample."""

    direction: Final[_Floats]
    pdf: Final[_Floats]
    weight: Final[_Floats]

@final
class EnvMap:
    """Environment map: radiance from every world direction, and importance
    sampling of directions ("latlong" as Mitsuba 3's envmap, "angular",
    "cube")."""

    def __new__(cls, image: ArrayLike | None = None, *, mapping: _Mapping = "latlong",
                to_world: Any = None, scale: float = 1.0, sampling: _Sampling | None = None,
                compensate: bool = False) -> EnvMap: ...
    @classmethod
    def load(cls, path: str | os.PathLike[str], *, layer: str | None = None,
             mapping: _Mapping = "latlong", to_world: Any = None, scale: float = 1.0,
             sampling: _Sampling | None = None, compensate: bool = False) -> EnvMap:
        """Reads an OpenEXR (of ``layer``), Radiance .hdr or PNG file."""
    def eval(self, d: ArrayLike, *, out: NDArray[Any] | None = None) -> _Floats:
        """Radiance from world directions d, (N, 3)."""
    def pdf(self, d: ArrayLike, *, out: NDArray[Any] | None = None) -> _Floats:
        """Density of sample per steradian, (N,)."""
    def sample(self, u: ArrayLike, *,
               out: tuple[NDArray[Any], NDArray[Any], NDArray[Any]] | None = None) -> EnvSample: ...
    def dir_to_uv(self, d: ArrayLike) -> _Floats:
        """Map coordinates of world directions, (N, 2)."""
    def uv_to_dir(self, uv: ArrayLike) -> _Floats:
        """World directions of map coordinates, (N, 3)."""
    def convert(self, mapping: _Mapping, resolution: int | tuple[int, int]) -> EnvMap: ...
    def _repr_png_(self) -> bytes: ...
    image: Final[NDArray[np.float32]]
    mapping: Final[_Mapping]
    sampling: Final[_Sampling]
    scale: Final[float]
    compensate: Final[bool]
    to_world: Final[NDArray[np.float64]]
