"""Monte Carlo estimators of the light an environment map delivers to a
point, and their quadrature references.

- :func:`irradiance` (strategies "uniform", "cosine", "emitter", "mis") and
  :func:`reflected_radiance` from a Phong surface ("bsdf", "emitter", "mis")
  run in Rust on all cores; same seed, same bits on any thread count.
  ``sampler=`` picks where the uniform numbers come from: "independent"
  (default), "stratified", "multijitter", "sobol", "ldsampler" or "zsobol" (see
  :mod:`mcsample.qmc` and :func:`mcsample.render`).
  "emitter" samples the environment map ("envmap" is accepted as the same);
  MIS weights by the power heuristic unless ``heuristic="balance"`` (the
  default of :func:`mcsample.render` too). Everything after ``n`` is
  keyword-only: ``irradiance(env, normal, n, strategy="emitter", seed=1)``.
- :func:`envmap_integral` integrates any function of direction against an
  environment map by quadrature over its sampling table's cells, where the
  map's radiance is one polynomial; :func:`irradiance_reference` and
  :func:`reflected_radiance_reference` use it.
"""

from __future__ import annotations

from typing import Any, Callable, Literal

import numpy as np
from numpy.typing import ArrayLike

from ._core import EnvMap, Phong
from ._core.estimators import Estimate, estimate as _estimate
from .seeds import SeedLike
from .stats import EnvMapDomain

Sampler = Literal["independent", "stratified", "multijitter", "sobol", "ldsampler", "zsobol"]

#: The end of both estimators' docstrings.
_COMMON_DOC = """heuristic : "power" (default) or "balance"
    sampler : "independent" (default), "stratified", "multijitter", "sobol", "ldsampler" or "zsobol"
        Where sample i's uniform numbers come from (dimensions 0, 1, ...;
        a BRDF sample's lobe is dimension 0, its direction the pair 1-2;
        see :func:`mcsample.render`).
        Independent keeps the bits of every earlier release. Under the
        others the n evaluations are stratified together: the estimate
        converges faster, and ``.stderr`` (the error of independent
        sampling) usually overstates its error; at most 2**32 - 1
        evaluations ("stratified", "multijitter": 2**30).
    first_sample : int, optional
        Estimate evaluations ``first_sample .. first_sample + n - 1`` of the
        run's sequence: a chunk of a longer run, whose partial sums the
        result keeps for :meth:`Estimate.merge` (chunks merged have the bits
        of one run). A multiple of 16384 (the evaluations of a partial sum).
    total_n : int, optional
        The length of that sequence (default ``first_sample + n``), which
        the stratified and Sobol' samplers lay their patterns over.

    Everything after ``n`` is keyword-only.

    Returns
    -------
    Estimate
        ``.value`` (3,) RGB, ``.stderr`` (3,), ``.n``, ``.strategy``."""


def irradiance(env: EnvMap, normal: ArrayLike, n: int, *,
               strategy: Literal["uniform", "cosine", "emitter", "envmap", "mis"] = "mis",
               seed: SeedLike = 0, heuristic: Literal["balance", "power"] = "power",
               sampler: Sampler = "independent", first_sample: int | None = None,
               total_n: int | None = None) -> Estimate:
    """The irradiance E = integral of L(w) max(0, n.w) dw at a surface of
    normal ``normal`` under ``env``, by Monte Carlo.

    Parameters
    ----------
    env : EnvMap
    normal : (3,) array_like, world space (normalised here)
    n : int >= 1
        Evaluations (an "mis" evaluation uses one cosine and one emitter
        sample).
    strategy : "uniform", "cosine", "emitter" or "mis" (default)
        "emitter" samples the map ("envmap" is the same).
    seed : int, None or numpy.random.Generator
        Seed of the samples (default 0); the result does not depend on the
        thread count. None draws a fresh seed from the operating system, a
        Generator draws one from itself.
    COMMON
    """
    return _estimate(env, normal, n, strategy=strategy, seed=seed, heuristic=heuristic,
                     sampler=sampler, first_sample=first_sample, total_n=total_n)


def reflected_radiance(env: EnvMap, phong: Phong, normal: ArrayLike, wi: ArrayLike, n: int, *,
                       strategy: Literal["bsdf", "emitter", "envmap", "mis"] = "mis",
                       seed: SeedLike = 0, heuristic: Literal["balance", "power"] = "power",
                       sampler: Sampler = "independent", first_sample: int | None = None,
                       total_n: int | None = None) -> Estimate:
    """The radiance L_r(wi) = integral of L(w) f_r(wi, w) max(0, n.w) dw that
    a Phong surface of normal ``normal`` reflects toward ``wi`` under ``env``.

    Parameters
    ----------
    env : EnvMap
    phong : Phong
    normal, wi : (3,) array_like, world space (normalised here); wi points
        toward the viewer
    n : int >= 1
    strategy : "bsdf", "emitter" or "mis" (default)
        "emitter" samples the map ("envmap" is the same).
    seed : int, None or numpy.random.Generator
        As for :func:`irradiance` (default 0).
    COMMON
    """
    if not isinstance(phong, Phong):
        raise TypeError(f"phong must be an mcsample.Phong, got {type(phong).__name__}")
    return _estimate(env, normal, n, phong=phong, wi=wi, strategy=strategy, seed=seed,
                     heuristic=heuristic, sampler=sampler, first_sample=first_sample,
                     total_n=total_n)


for _f in (irradiance, reflected_radiance):
    _f.__doc__ = (_f.__doc__ or "").replace("COMMON", _COMMON_DOC)

__all__ = [
    "Estimate",
    "envmap_integral",
    "irradiance",
    "irradiance_reference",
    "reflected_radiance",
    "reflected_radiance_reference",
]


def envmap_integral(env: Any, f: Callable[[np.ndarray], Any], k: int = 4,
                    batch: int = 1 << 20) -> Any:
    """The integral over the sphere of ``f(d)`` (d: (m, 3) world directions;
    f returns (m,) or (m, c)) by the midpoint rule on k x k points in every
    cell of ``env``'s sampling table (:class:`mcsample.stats.EnvMapDomain`).
    Exact for the map's own pdf, and accurate for integrands built on its
    radiance, whose texel-scale features the cells follow."""
    domain = EnvMapDomain(env)
    ny, nx = domain.cells[0] * k, domain.cells[1] * k
    (x0, x1), (y0, y1) = domain.bounds
    xs = x0 + (np.arange(nx) + 0.5) / nx * (x1 - x0)
    rows_per_batch = max(1, batch // nx)
    total: Any = 0.0
    for start in range(0, ny, rows_per_batch):
        ys = y0 + (np.arange(start, min(ny, start + rows_per_batch)) + 0.5) / ny * (y1 - y0)
        gx, gy = np.meshgrid(xs, ys)
        xy = np.stack([gx.ravel(), gy.ravel()], axis=1)
        values = np.asarray(f(domain.from_param(xy)), dtype=np.float64)
        jacobian = domain.jacobian(xy)
        values = values * (jacobian[:, None] if values.ndim == 2 else jacobian)
        total = total + values.sum(axis=0)
    return total * (x1 - x0) * (y1 - y0) / (nx * ny)


def irradiance_reference(env: Any, normal: Any, k: int = 4) -> np.ndarray:
    """Irradiance at a surface of ``normal`` by quadrature (see
    :func:`envmap_integral`): (3,) RGB."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    return envmap_integral(env, lambda d: env.eval(d) * np.maximum(d @ n, 0)[:, None], k)


def reflected_radiance_reference(env: Any, phong: Any, normal: Any, wi: Any,
                                 k: int = 4) -> np.ndarray:
    """Radiance a Phong surface of ``normal`` reflects toward ``wi`` by
    quadrature (see :func:`envmap_integral`): (3,) RGB. Resolves lobes about
    as wide as the map's texels (raise ``k`` for sharper ones)."""
    from ._core import Frame

    n = np.asarray(normal, dtype=np.float64)
    frame = Frame(n / np.linalg.norm(n))
    wi_local = frame.to_local(np.asarray(wi, dtype=np.float64) / np.linalg.norm(wi))

    def integrand(d: np.ndarray) -> np.ndarray:
        wo = frame.to_local(d)
        return env.eval(d) * phong.eval(wi_local, wo) * np.maximum(wo[:, 2], 0)[:, None]

    return envmap_integral(env, integrand, k)
