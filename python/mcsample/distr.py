"""Distributions: the tables of the compiled core, and rejection sampling of
a density given as a Python callable.

- :class:`Discrete1D`: CDF inversion (guide table + binary search);
  ``sample``, ``sample_reuse``, ``pmf``, ``cdf``, ``sum``.
- :class:`AliasTable`: Walker's alias method (built by sweeping), O(1) per sample.
- :class:`Discrete2D`: a row from the marginal, then a column.
- :class:`PiecewiseConstant1D` / :class:`PiecewiseConstant2D`: densities
  constant on equal cells, sampled by inverting their CDFs, with ``pdf`` and
  ``invert``.
- :func:`rejection_sample`: darts under a bounded density.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence, Union

import numpy as np

from ._args import integer
from ._core import AliasTable, Discrete1D, Discrete2D, PiecewiseConstant1D, PiecewiseConstant2D, Rng

__all__ = [
    "AliasTable",
    "Discrete1D",
    "Discrete2D",
    "PiecewiseConstant1D",
    "PiecewiseConstant2D",
    "rejection_sample",
]

#: Proposals per batch are capped at this many, to bound memory.
_MAX_BATCH = 1 << 22

Box = Union[Sequence[float], Sequence[Sequence[float]]]


def _box(domain: Box) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) arrays of an interval (a, b) or a rectangle
    ((x0, x1), (y0, y1))."""
    try:
        arr = np.asarray(domain, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"domain = {domain!r}: expected (a, b) or ((x0, x1), (y0, y1))") from None
    if arr.shape == (2,):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] not in (1, 2):
        raise ValueError(f"domain = {domain!r}: expected (a, b) or ((x0, x1), (y0, y1))")
    lo, hi = arr[:, 0], arr[:, 1]
    if not (np.all(np.isfinite(arr)) and np.all(lo < hi)):
        raise ValueError(f"domain = {domain!r}: needs finite bounds with lower < upper")
    return lo, hi


def rejection_sample(
    pdf: Callable[[np.ndarray], Any],
    bound: float,
    domain: Box,
    n: int,
    seed: int = 0,
) -> tuple[np.ndarray, float]:
    """Samples of a density by rejection: uniform darts (x, y) in the box
    domain × [0, bound], keeping x where y < pdf(x).

    Proposals are drawn and ``pdf`` is evaluated in vectorised batches, sized
    from the acceptance rate seen so far. The expected acceptance rate is
    (integral of pdf over the domain) / (bound × volume of the domain).

    Parameters
    ----------
    pdf : callable
        Maps points, ndarray (m,) on an interval or (m, 2) on a rectangle
        (float64), to densities (m,), finite, >= 0 and <= ``bound``. It need
        not be normalised.
    bound : float
        An upper bound of ``pdf`` on the domain, finite and > 0.
    domain : (a, b) or ((x0, x1), (y0, y1))
        The interval or rectangle.
    n : int
        Number of samples wanted (>= 0).
    seed : int
        Seed of the PCG32 stream of proposals (``mcsample.Rng(seed)``).

    Returns
    -------
    (samples, acceptance)
        samples: ndarray (n,) on an interval or (n, 2) on a rectangle,
        float64; acceptance: accepted / proposed over all proposals drawn.

    Raises
    ------
    ValueError
        For a bad bound, domain or n; when ``pdf`` returns a value that is
        NaN, negative or above ``bound`` (naming the point); or when no
        proposal at all is accepted in 10^8 tries (a density that is zero
        on the domain).
    """
    try:
        bound = float(bound)
    except (TypeError, ValueError):
        raise TypeError(f"bound must be a number, got {bound!r}") from None
    if not (np.isfinite(bound) and bound > 0):
        raise ValueError(f"bound = {bound}: must be finite and > 0")
    n = integer(n, "n")
    lo, hi = _box(domain)
    dim = len(lo)
    rng = Rng(seed)
    chunks: list[np.ndarray] = []
    accepted = proposed = 0
    while accepted < n:
        rate = accepted / proposed if accepted else 0.0
        if proposed >= 100_000_000 and accepted == 0:
            raise ValueError("pdf: no proposal accepted in 1e8 tries; is the density zero "
                             "on the domain?")
        want = (n - accepted) / rate * 1.1 if rate > 0 else max(4 * (n - accepted), 1024)
        m = int(min(max(want, 1024), _MAX_BATCH))
        x = lo + (hi - lo) * rng.random((m, dim))
        points = x[:, 0] if dim == 1 else x
        values = np.asarray(pdf(points), dtype=np.float64).reshape(-1)
        if values.shape != (m,):
            raise ValueError(f"pdf must return one value per point: {m} points gave shape "
                             f"{np.shape(values)}")
        bad = ~((values >= 0) & (values <= bound))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"pdf({points[i].tolist()}) = {values[i]}: the density must lie in "
                             f"[0, bound = {bound}] (point {i} of a batch of {m})")
        keep = rng.random(m) * bound < values
        chunks.append(points[keep])
        accepted += int(np.count_nonzero(keep))
        proposed += m
    samples = np.concatenate(chunks)[:n] if chunks else np.zeros((0,) if dim == 1 else (0, 2))
    return samples, (accepted / proposed if proposed else float("nan"))
