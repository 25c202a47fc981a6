"""Quasi-Monte Carlo engines with the interface of ``scipy.stats.qmc``.

Each engine is a ``scipy.stats.qmc.QMCEngine`` (so ``qmc.scale``,
``qmc.discrepancy`` and scipy's QMC-based samplers take it), computes its
points in Rust on all cores from their index alone (the same bits at any
thread count; ``fast_forward`` costs O(1)), and draws float64 or, with
``dtype=np.float32``, float32 points in ``[0, 1)``.

- ``Sobol(d, scramble=True, seed=None)``: Joe and Kuo's direction numbers in
  scipy's Gray-code order. ``scramble=True`` is Owen's nested uniform
  scrambling (a hash per dimension: Vegdahl's Laine-Karras hash, as
  pbrt-v4's FastOwenScrambler), ``"lms"`` a random linear matrix scramble with a digital
  shift (scipy's kind of scrambling, other random bits), ``False`` the
  plain sequence: ``scipy.stats.qmc.Sobol(d, scramble=False)``'s points,
  bit for bit. At most 2**32 points.
- ``Halton(d, scramble=True, seed=None)``: the first ``d`` primes as bases;
  ``scramble=True`` permutes the digits at random per digit position and
  dimension (as scipy does), ``False`` gives ``scipy.stats.qmc.Halton(d,
  scramble=False)``'s points, bit for bit.

The stratified patterns are drawn whole: each ``random(n)`` is one
pattern of ``n`` points (its seed derived from the engine's and from the
points drawn before it, so ``reset()`` replays the same calls):

- ``LatinHypercube(d, scramble=True, seed=None)``: one point per interval
  of length 1/n in every dimension, jittered (``scramble=False``: at the
  intervals' centres), as scipy's ``LatinHypercube``.
- ``Stratified(d, seed=None)``: Mitsuba's ``stratified`` sampler, the
  strata of an r x r grid (r = ceil(sqrt(n))) in a random order per pair of
  dimensions, jittered (one point per stratum when n is a square).
- ``MultiJitter(d, seed=None)``: Kensler's correlated multi-jittered
  points per pair of dimensions, as Mitsuba's ``multijitter`` sampler.

Seeds are an int, None (fresh entropy) or a ``numpy.random.Generator``, as
everywhere in mcsample; the same seed gives the same points.
"""

from __future__ import annotations

from typing import Literal, Union

import numpy as np
import numpy.typing as npt
from scipy.stats import qmc as _scipy_qmc

from ._core import qmc as _core
from ._args import integer
from .seeds import SeedLike, resolve_seed

__all__ = ["Sobol", "Halton", "LatinHypercube", "Stratified", "MultiJitter"]

DType = Union[type[np.float64], type[np.float32], np.dtype, str]


class _Engine(_scipy_qmc.QMCEngine):
    """The shared part: position, ``random``, ``fast_forward``, ``reset``."""

    _points: _core.Points
    seed: int
    """The 64-bit seed the scramble was drawn from."""

    def __init__(self, points: _core.Points, seed: int) -> None:
        self._points = points
        self.seed = seed
        super().__init__(d=points.d)

    def _random(self, n: int = 1, *, workers: int = 1) -> np.ndarray:
        return self._points.points(self.num_generated, integer(n, "n"))

    def random(
        self, n: int = 1, *, workers: int = 1, dtype: DType = np.float64
    ) -> np.ndarray:
        """The next ``n`` points.

        Parameters
        ----------
        n : int >= 0
        workers : int
            Ignored (scipy's argument): mcsample uses its own thread count
            (``mcsample.set_num_threads``).
        dtype : np.float64 (default) or np.float32

        Returns
        -------
        ndarray, shape (n, d), in [0, 1).
        """
        n = integer(n, "n")
        sample = self._points.points(self.num_generated, n, dtype)
        self.num_generated += n
        return sample

    def fast_forward(self, n: int) -> _Engine:
        """Skips ``n`` points (n >= 0) in O(1); returns the engine. (For the
        patterns, which are drawn whole, it changes which pattern comes
        next.)"""
        self.num_generated += integer(n, "n")
        return self

    def reset(self) -> _Engine:
        """Back to the first point (the scramble stays); returns the engine."""
        self.num_generated = 0
        return self

    def __repr__(self) -> str:
        scramble = "" if self._scramble is None else f"scramble={self._scramble!r}, "
        return (f"{type(self).__name__}(d={self.d}, {scramble}seed={self.seed}) "
                f"at point {self.num_generated}")

    _scramble: object = None
    """The ``scramble`` argument, for the repr (None: the engine has none)."""


class Sobol(_Engine):
    """Sobol' points (Joe and Kuo's direction numbers, scipy's order).

    Parameters
    ----------
    d : int
        Dimensions, 1 to ``Sobol.MAXDIM`` (21201).
    scramble : True (default), "lms" or False, keyword only
        Owen's nested uniform scrambling; a random linear matrix scramble
        with a digital shift; or the plain sequence (scipy's
        ``scramble=False`` points, bit for bit, starting at the origin).
    seed : int, None or numpy.random.Generator, keyword only
        The scramble's random bits; None (default) draws fresh ones.

    Points are multiples of 2**-32 (float32: 2**-23); at most 2**32 of them.
    """

    MAXDIM = 21201

    def __init__(
        self, d: int, *, scramble: bool | Literal["lms"] = True, seed: SeedLike = None
    ) -> None:
        kind: Literal["sobol-owen", "sobol", "sobol-lms"]
        if isinstance(scramble, (bool, np.bool_)):
            kind = "sobol-owen" if scramble else "sobol"
        elif scramble == "lms":
            kind = "sobol-lms"
        else:
            raise ValueError(f'scramble = {scramble!r}: must be True, "lms" or False')
        self._scramble = scramble
        value = resolve_seed(seed)
        super().__init__(_core.Points(kind, d, value), value)

    def random_base2(self, m: int, *, dtype: DType = np.float64) -> np.ndarray:
        """The next ``2**m`` points, keeping the count drawn a power of two.

        Raises ValueError if the points drawn before and after are not
        both powers of two (the balance of a Sobol' net needs them), as
        scipy does.
        """
        m = integer(m, "m")
        if m > 32:
            raise ValueError(f"m = {m}: must be at most 32 (2**32 points in all)")
        n = 2**m
        total = self.num_generated + n
        if total & (total - 1) != 0:
            raise ValueError(
                f"m = {m}: {self.num_generated} points were drawn before, and "
                f"{self.num_generated} + 2**{m} = {total} is not a power of 2 "
                "(use random(n) to draw them anyway)")
        return self.random(n, dtype=dtype)


class Halton(_Engine):
    """Halton points, the first ``d`` primes as bases.

    Parameters
    ----------
    d : int
        Dimensions, 1 to 65536.
    scramble : bool, keyword only
        True (default): a random permutation of the digits per digit
        position and dimension; False: scipy's ``scramble=False`` points,
        bit for bit (starting at the origin).
    seed : int, None or numpy.random.Generator, keyword only
        The permutations' random bits; None (default) draws fresh ones.
    """

    def __init__(self, d: int, *, scramble: bool = True, seed: SeedLike = None) -> None:
        if not isinstance(scramble, (bool, np.bool_)):
            raise ValueError(f"scramble = {scramble!r}: must be True or False")
        self._scramble = bool(scramble)
        value = resolve_seed(seed)
        super().__init__(_core.Points("halton-permuted" if scramble else "halton", d, value), value)


class LatinHypercube(_Engine):
    """Latin hypercube patterns: each ``random(n)`` puts one point in each
    interval of length 1/n of every dimension.

    Parameters
    ----------
    d : int
        Dimensions, 1 to 65536.
    scramble : bool, keyword only
        True (default): a uniform point in each interval; False: its centre
        (scipy's meaning).
    seed : int, None or numpy.random.Generator, keyword only
        None (default) draws fresh random bits.
    """

    def __init__(self, d: int, *, scramble: bool = True, seed: SeedLike = None) -> None:
        if not isinstance(scramble, (bool, np.bool_)):
            raise ValueError(f"scramble = {scramble!r}: must be True or False")
        self._scramble = bool(scramble)
        value = resolve_seed(seed)
        kind: Literal["lhs", "lhs-centered"] = "lhs" if scramble else "lhs-centered"
        super().__init__(_core.Points(kind, d, value), value)


_PATTERN_PARAMETERS = """
    Parameters
    ----------
    d : int
        Dimensions, 1 to 65536.
    seed : int, None or numpy.random.Generator, keyword only
        None (default) draws fresh random bits.
    """


class _Pattern(_Engine):
    """An engine of patterns of one kind (``_kind``) and no options; a
    subclass's docstring is its summary followed by ``_PATTERN_PARAMETERS``."""

    _kind: Literal["stratified", "multijitter"]

    def __init__(self, d: int, *, seed: SeedLike = None) -> None:
        value = resolve_seed(seed)
        super().__init__(_core.Points(self._kind, d, value), value)


class Stratified(_Pattern):
    __doc__ = """Jittered strata, as Mitsuba's ``stratified`` sampler: each
    ``random(n)`` shuffles the strata of an r x r grid (r = ceil(sqrt(n)))
    per pair of dimensions and jitters each point in its stratum (a last odd
    dimension is stratified in n intervals). With n a square every stratum
    gets one point.
    """ + _PATTERN_PARAMETERS

    _kind = "stratified"


class MultiJitter(_Pattern):
    __doc__ = """Kensler's correlated multi-jittered points (2013), as Mitsuba's
    ``multijitter`` sampler: per pair of dimensions, each ``random(n)`` is
    stratified in an m x k grid (m = floor(sqrt(n)), k = ceil(n/m)) and in
    n intervals along y (and along x when n = m k).
    """ + _PATTERN_PARAMETERS

    _kind = "multijitter"
