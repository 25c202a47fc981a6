"""Monte Carlo estimators of the light an environment map delivers to a
point, and their quadrature references.

- :func:`irradiance` (strategies "uniform", "cosine", "emitter", "mis") and
  :func:`reflected_radiance` from a Phong surface ("bsdf", "emitter", "mis")
  run in Rust on all cores; same seed, same bits on any thread count.
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

from typing import Any, Callable

import numpy as np

from ._core.estimators import Estimate, irradiance, reflected_radiance
from .stats import EnvMapDomain

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
