"""Statistics that prove samplers right, for mcsample's own and for yours.

- :func:`chi2_test`: Pearson's chi-square goodness of fit of a sampler
  against its density, by the method of Mitsuba 3's ``mitsuba.chi2``: map the
  samples to a 2D parameter box, histogram them, integrate the density over
  each cell (trapezoid rule, ``ires`` points per cell and axis), pool cells
  with an expected count below 5, and compare the p-value with a
  Šidák-corrected significance level.
- :func:`two_sample_test`: the chi-square test of homogeneity of two samplers
  that have no density.
- image comparison: :func:`mse`, :func:`relmse`, :func:`image_ztest`, and
  :func:`render_ztest` for two renders.

Domains map target points to a parameter box whose boundary is the domain's
boundary (so no cell straddles an edge of the support) and give the Jacobian
from the box's measure to the target measure (per steradian on the sphere,
per unit area on the plane, per unit length on an interval).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Sequence, Union

import numpy as np

from ._core import uniform

__all__ = [
    "Chi2Result",
    "DiskDomain",
    "Domain",
    "EnvMapDomain",
    "HemisphereDomain",
    "ImageZTestResult",
    "IntervalDomain",
    "PlanarDomain",
    "SphericalDomain",
    "chi2_test",
    "image_ztest",
    "luminance",
    "make_domain",
    "mse",
    "relmse",
    "render_ztest",
    "two_sample_test",
]


# --------------------------------------------------------------------------
# Domains


class Domain:
    """A target domain and its measure-preserving parameterisation on the box
    ``bounds = ((x0, x1), (y0, y1))``. Subclass it for other domains: define
    ``bounds``, ``aspect``, ``to_param`` and ``from_param``."""

    #: ((x0, x1), (y0, y1)) of the parameter box.
    bounds: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 1.0), (0.0, 1.0))
    #: Columns per row of the histogram (None: one row, a 1D domain).
    aspect: float | None = 1.0
    #: Dimension of the points ``sample`` returns (1 for intervals).
    point_dim: int = 2

    def to_param(self, points: np.ndarray) -> np.ndarray:
        """Points (n, point_dim) → parameters (n, 2)."""
        raise NotImplementedError

    def from_param(self, xy: np.ndarray) -> np.ndarray:
        """Parameters (n, 2) → points (n, point_dim)."""
        raise NotImplementedError

    def jacobian(self, xy: np.ndarray) -> np.ndarray | float:
        """Target measure per unit parameter area at ``xy`` (1 when the map
        preserves measure)."""
        return 1.0

    def check_points(self, points: np.ndarray) -> str | None:
        """A message if the points are not of this domain's kind, else None."""
        return None

    def __repr__(self) -> str:
        return f"{type(self).__name__}(bounds={self.bounds})"


class IntervalDomain(Domain):
    """The interval [a, b]; densities per unit length."""

    aspect = None
    point_dim = 1

    def __init__(self, a: float = 0.0, b: float = 1.0):
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise ValueError(f"domain = ({a}, {b}): an interval needs finite a < b")
        self.bounds = ((float(a), float(b)), (-0.5, 0.5))

    def to_param(self, points: np.ndarray) -> np.ndarray:
        x = points.reshape(-1)
        return np.stack([x, np.zeros_like(x)], axis=1)

    def from_param(self, xy: np.ndarray) -> np.ndarray:
        return xy[:, 0].copy()


class PlanarDomain(Domain):
    """A rectangle ((x0, x1), (y0, y1)) of the plane, the identity map;
    densities per unit area. The unit disk uses [-1, 1]^2."""

    def __init__(self, bounds: Sequence[Sequence[float]] = ((0.0, 1.0), (0.0, 1.0))):
        (x0, x1), (y0, y1) = bounds
        if not all(np.isfinite(v) for v in (x0, x1, y0, y1)) or x0 >= x1 or y0 >= y1:
            raise ValueError(f"domain = {bounds!r}: a rectangle needs finite x0 < x1, y0 < y1")
        self.bounds = ((float(x0), float(x1)), (float(y0), float(y1)))
        self.aspect = (x1 - x0) / (y1 - y0)

    def to_param(self, points: np.ndarray) -> np.ndarray:
        return points

    def from_param(self, xy: np.ndarray) -> np.ndarray:
        return xy


class DiskDomain(Domain):
    """The unit disk, parameterised by (phi, r^2) ∈ [-pi, pi] × [0, 1], whose
    area element is dA = r dr dphi = (1/2) d(r^2) dphi; densities per unit
    area. The disk's rim is the box's edge, so no cell straddles it."""

    bounds = ((-np.pi, np.pi), (0.0, 1.0))
    aspect = 1.0

    def to_param(self, points: np.ndarray) -> np.ndarray:
        return np.stack([np.arctan2(points[:, 1], points[:, 0]),
                         points[:, 0] ** 2 + points[:, 1] ** 2], axis=1)

    def from_param(self, xy: np.ndarray) -> np.ndarray:
        r = np.sqrt(np.maximum(xy[:, 1], 0.0))
        return np.stack([r * np.cos(xy[:, 0]), r * np.sin(xy[:, 0])], axis=1)

    def jacobian(self, xy: np.ndarray) -> float:
        return 0.5


class SphericalDomain(Domain):
    """The unit sphere, parameterised by (phi, y) ∈ [-pi, pi] × [-1, 1] with
    1 - cos theta = 2 ((1 - y) / 2)^zoom; densities per steradian.

    ``zoom = 1`` (the default) is Archimedes' area-preserving map, y =
    cos theta. A larger ``zoom`` spends the histogram's rows near +z, which a
    sharp lobe around +z (cos^n with n in the hundreds or thousands) needs
    to be resolved; rotate the samples so that the lobe's axis is +z (e.g.
    with ``mcsample.Frame``).
    """

    bounds = ((-np.pi, np.pi), (-1.0, 1.0))
    aspect = 2.0
    point_dim = 3

    def __init__(self, zoom: float = 1.0):
        if not (np.isfinite(zoom) and zoom >= 1.0):
            raise ValueError(f"zoom = {zoom}: must be finite and >= 1")
        self.zoom = float(zoom)

    @property
    def _span(self) -> float:
        """1 - (lowest cos theta): 2 on the sphere, 1 on the hemisphere."""
        return 1.0 - self.bounds[1][0]

    def to_param(self, points: np.ndarray) -> np.ndarray:
        # Points below the domain map below its box (and are reported).
        one_minus_z = np.maximum(1.0 - points[:, 2], 0.0)
        y = 1.0 - self._span * (one_minus_z / self._span) ** (1.0 / self.zoom)
        return np.stack([np.arctan2(points[:, 1], points[:, 0]), y], axis=1)

    def from_param(self, xy: np.ndarray) -> np.ndarray:
        t = np.clip((1.0 - xy[:, 1]) / self._span, 0.0, 1.0)
        z = 1.0 - self._span * t ** self.zoom
        r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
        return np.stack([r * np.cos(xy[:, 0]), r * np.sin(xy[:, 0]), z], axis=1)

    def jacobian(self, xy: np.ndarray) -> np.ndarray | float:
        # d(cos theta)/dy: steradians per unit parameter area.
        if self.zoom == 1.0:
            return 1.0
        t = np.clip((1.0 - xy[:, 1]) / self._span, 0.0, 1.0)
        return self.zoom * t ** (self.zoom - 1.0)

    def check_points(self, points: np.ndarray) -> str | None:
        norm = np.linalg.norm(points, axis=1)
        bad = np.flatnonzero(~(np.abs(norm - 1.0) < 1e-3))
        if bad.size:
            i = bad[0]
            return (f"{bad.size} of {len(points)} samples are not unit vectors "
                    f"(first: sample[{i}] = {points[i].tolist()}, length {norm[i]:.6g})")
        return None

    def __repr__(self) -> str:
        zoom = f"zoom={self.zoom}" if self.zoom != 1.0 else ""
        return f"{type(self).__name__}({zoom})"


class HemisphereDomain(SphericalDomain):
    """The +z hemisphere, parameterised by (phi, y) ∈ [-pi, pi] × [0, 1] with
    cos theta = 1 - (1 - y)^zoom; densities per steradian.

    ``zoom = 1`` (the default) is Archimedes' area-preserving map, y =
    cos theta. A larger ``zoom`` spends the histogram's rows near the pole,
    which a sharp lobe around +z (cos^n with n in the hundreds or thousands)
    needs to be resolved: its width in y is about n^(-1/zoom).
    """

    bounds = ((-np.pi, np.pi), (0.0, 1.0))
    aspect = 1.0


class EnvMapDomain(Domain):
    """The sphere in the coordinates of an environment map's sampling table,
    where its piecewise density is constant on cells: lat-long, Mitsuba's
    (u, v); angular, polar coordinates around the probe's +Z, (psi, rho) =
    (atan2(y, x) / 2 pi, acos(z) / pi); cube, (u, face + v). Densities per
    steradian.

    ``cells`` is a histogram resolution whose cells each lie in one cell of
    the table (lat-long: half-texel columns, rows between texel rows;
    angular: 2W sectors x W rings; cube: half-texel cells), so that the
    expected counts of a ``sampling="piecewise"`` map are integrated exactly:
    ``chi2_test(..., EnvMapDomain(env), res=EnvMapDomain(env).cells)``.
    """

    point_dim = 3

    def __init__(self, env: Any):
        self.env = env
        self.mapping = env.mapping
        self.rotation = np.asarray(env.to_world, dtype=np.float64)
        shape = np.shape(env.image)
        if self.mapping == "cube":
            r = shape[1]
            self.bounds = ((0.0, 1.0), (0.0, 6.0))
            self.cells: tuple[int, int] = (2 * r, 12 * r)
        elif self.mapping == "angular":
            self.bounds = ((0.0, 1.0), (0.0, 1.0))
            self.cells = (max(2 * shape[1], 4), max(shape[1], 2))
        else:
            h, w = shape[:2]
            self.bounds = ((0.0, 1.0), (0.0, 1.0))
            self.cells = (2 * w, h - 1)
        (x0, x1), (y0, y1) = self.bounds
        self.aspect = (x1 - x0) / (y1 - y0)

    def to_param(self, points: np.ndarray) -> np.ndarray:
        if self.mapping != "angular":
            return np.asarray(self.env.dir_to_uv(points), dtype=np.float64)
        d = points @ self.rotation  # local = R^T d
        psi = np.arctan2(d[:, 1], d[:, 0]) / (2 * np.pi) % 1.0
        rho = np.arctan2(np.hypot(d[:, 0], d[:, 1]), d[:, 2]) / np.pi
        return np.stack([psi, rho], axis=1)

    def from_param(self, xy: np.ndarray) -> np.ndarray:
        if self.mapping != "angular":
            return np.asarray(self.env.uv_to_dir(xy), dtype=np.float64)
        psi, rho = 2 * np.pi * xy[:, 0], np.pi * xy[:, 1]
        local = np.stack([np.cos(psi) * np.sin(rho), np.sin(psi) * np.sin(rho), np.cos(rho)], 1)
        return local @ self.rotation.T

    def jacobian(self, xy: np.ndarray) -> np.ndarray:
        if self.mapping == "cube":
            sc, tc = 2 * xy[:, 0] - 1, 2 * (xy[:, 1] % 1.0) - 1
            return 4 / (1 + sc**2 + tc**2) ** 1.5
        return 2 * np.pi**2 * np.sin(np.pi * xy[:, 1])

    def check_points(self, points: np.ndarray) -> str | None:
        return SphericalDomain.check_points(self, points)  # type: ignore[arg-type]

    def __repr__(self) -> str:
        return f"EnvMapDomain({self.mapping!r}, cells={self.cells})"


DomainLike = Union[str, Domain, Sequence[Any]]


def make_domain(domain: DomainLike) -> Domain:
    """A :class:`Domain` from a name ("interval" [0, 1], "square" [0, 1]^2,
    "disk" (the unit disk, :class:`DiskDomain`), "plane" ([-1, 1]^2), "sphere",
    "hemisphere"), an interval ``(a, b)``, a rectangle ``((x0, x1), (y0, y1))``
    or a Domain (returned as is)."""
    if isinstance(domain, Domain):
        return domain
    if isinstance(domain, str):
        named: dict[str, Callable[[], Domain]] = {
            "interval": IntervalDomain,
            "square": PlanarDomain,
            "disk": DiskDomain,
            "plane": lambda: PlanarDomain(((-1.0, 1.0), (-1.0, 1.0))),
            "sphere": SphericalDomain,
            "hemisphere": HemisphereDomain,
        }
        if domain not in named:
            raise ValueError(f"domain = {domain!r}: expected one of {sorted(named)}, "
                             "an interval (a, b) or a rectangle ((x0, x1), (y0, y1))")
        return named[domain]()
    try:
        parts = [tuple(p) if np.ndim(p) else p for p in domain]
    except TypeError:
        raise TypeError(f"domain must be a name, a Domain or a tuple, got {domain!r}") from None
    if len(parts) == 2 and all(np.ndim(p) == 0 for p in parts):
        return IntervalDomain(float(parts[0]), float(parts[1]))
    if len(parts) == 2 and all(np.ndim(p) == 1 and len(p) == 2 for p in parts):
        return PlanarDomain(parts)
    raise ValueError(f"domain = {domain!r}: expected (a, b) or ((x0, x1), (y0, y1))")


def _grid_shape(domain: Domain, res: int | tuple[int, int]) -> tuple[int, int]:
    """(columns, rows) of the histogram."""
    if isinstance(res, tuple):
        nx, ny = res
    elif domain.aspect is None:
        nx, ny = res, 1
    else:
        nx, ny = max(int(round(res * domain.aspect)), 1), res
    if domain.aspect is None:
        ny = 1
    if nx < 1 or ny < 1:
        raise ValueError(f"res = {res!r}: needs at least one cell per axis")
    return int(nx), int(ny)


def _histogram(domain: Domain, points: np.ndarray, shape: tuple[int, int],
               messages: list[str], name: str) -> np.ndarray:
    """Counts (rows, columns) of `points` in the parameter grid; notes points
    outside the domain or not finite in `messages`."""
    points = np.asarray(points, dtype=np.float64)
    if domain.point_dim == 1:
        if points.ndim == 2 and points.shape[1] == 1:
            points = points[:, 0]
        if points.ndim != 1:
            raise ValueError(f"{name} must return shape (n,) on an interval, got {points.shape}")
    elif points.ndim != 2 or points.shape[1] != domain.point_dim:
        raise ValueError(f"{name} must return shape (n, {domain.point_dim}), got {points.shape}")
    finite = np.all(np.isfinite(points.reshape(len(points), -1)), axis=1)
    if not finite.all():
        i = int(np.flatnonzero(~finite)[0])
        messages.append(f"{np.count_nonzero(~finite)} samples are NaN or infinite "
                        f"(first: sample[{i}] = {points[i].tolist()})")
    kind = domain.check_points(points[finite])
    if kind:
        messages.append(kind)
    xy = domain.to_param(points[finite])
    (x0, x1), (y0, y1) = domain.bounds
    lo, hi = np.array([x0, y0]), np.array([x1, y1])
    eps = (hi - lo) * 1e-4
    inside = np.all((xy >= lo - eps) & (xy <= hi + eps), axis=1)
    if not inside.all():
        i = int(np.flatnonzero(~inside)[0])
        messages.append(f"{np.count_nonzero(~inside)} of {len(points)} samples lie outside "
                        f"the domain {domain!r} (first: {points[finite][i].tolist()})")
    nx, ny = shape
    t = (xy[inside] - lo) / (hi - lo)
    ix = np.clip((t[:, 0] * nx).astype(np.int64), 0, nx - 1)
    iy = np.clip((t[:, 1] * ny).astype(np.int64), 0, ny - 1)
    return np.bincount(iy * nx + ix, minlength=nx * ny).reshape(ny, nx).astype(np.float64)


def _integrate_pdf(domain: Domain, pdf: Callable[[np.ndarray], Any], shape: tuple[int, int],
                   ires: int) -> np.ndarray:
    """Integral of `pdf` over each cell (rows, columns), by the trapezoid rule
    with `ires` points per cell and axis (one point across a 1D domain)."""
    nx, ny = shape
    (x0, x1), (y0, y1) = domain.bounds
    one_d = domain.aspect is None
    iy_res = 1 if one_d else ires
    # Points slightly inside each cell, so that a density discontinuous on
    # a cell boundary (a hemisphere's rim) is evaluated on the proper side.
    sx = (np.arange(ires) + 1e-4) * (1 - 2e-4) / (ires - 1)
    sy = (np.arange(iy_res) + 1e-4) * (1 - 2e-4) / (ires - 1) if not one_d else np.array([0.5])
    wx = np.where((np.arange(ires) == 0) | (np.arange(ires) == ires - 1), 0.5, 1.0) / (ires - 1)
    wy = (np.where((np.arange(ires) == 0) | (np.arange(ires) == ires - 1), 0.5, 1.0) / (ires - 1)
          if not one_d else np.array([1.0]))
    hx, hy = (x1 - x0) / nx, (y1 - y0) / ny
    px = x0 + (np.arange(nx)[:, None] + sx[None, :]) * hx  # (nx, ires)
    py = y0 + (np.arange(ny)[:, None] + sy[None, :]) * hy  # (ny, iy_res)
    gx, gy = np.meshgrid(px.reshape(-1), py.reshape(-1))  # (ny*iy, nx*ires)
    xy = np.stack([gx.reshape(-1), gy.reshape(-1)], axis=1)
    values = np.asarray(pdf(domain.from_param(xy)), dtype=np.float64).reshape(-1)
    if values.shape[0] != xy.shape[0]:
        raise ValueError(f"pdf must return one value per point: {xy.shape[0]} points "
                         f"gave shape {np.shape(values)}")
    values = values * domain.jacobian(xy)
    values = values.reshape(ny, iy_res, nx, ires)
    cell_area = hx * (1.0 if one_d else hy)
    weights = wy[None, :, None, None] * wx[None, None, None, :]
    return (values * weights).sum(axis=(1, 3)) * cell_area


def _pooled_chi2(observed: np.ndarray, expected: np.ndarray,
                 threshold: float = 5.0) -> tuple[float, int, int, int]:
    """Pearson's statistic over cells sorted by expected count, pooling
    consecutive cells below `threshold` until their pooled expectation passes
    it (leftover cells are dropped, as Mitsuba does). Returns
    (statistic, dof, cells pooled, pooled cells made)."""
    order = np.argsort(expected, kind="stable")
    obs, exp = observed[order], expected[order]
    high = exp >= threshold
    stat = float(np.sum((obs[high] - exp[high]) ** 2 / exp[high]))
    terms = int(np.count_nonzero(high))
    low = ~high & ((obs != 0) | (exp != 0))
    pooled_obs = pooled_exp = 0.0
    pooled_in = pooled_out = 0
    for o, e in zip(obs[low], exp[low]):
        pooled_obs += o
        pooled_exp += e
        pooled_in += 1
        if pooled_exp > threshold:
            stat += (pooled_obs - pooled_exp) ** 2 / pooled_exp
            pooled_obs = pooled_exp = 0.0
            pooled_out += 1
            terms += 1
    return stat, terms - 1, pooled_in, pooled_out


def _chi2_sf(statistic: float, dof: int) -> float:
    from scipy.special import chdtrc

    return float(chdtrc(dof, statistic))


def _sidak(alpha: float, test_count: int) -> float:
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha = {alpha}: must lie in (0, 1)")
    if int(test_count) < 1:
        raise ValueError(f"test_count = {test_count}: must be >= 1")
    return 1.0 - (1.0 - alpha) ** (1.0 / int(test_count))


# --------------------------------------------------------------------------
# Results


@dataclass
class Chi2Result:
    """Outcome of :func:`chi2_test` or :func:`two_sample_test`.

    ``histogram`` and ``expected`` are (rows, columns) arrays over the
    domain's parameter box (cos theta along rows, phi along columns on the
    sphere); for :func:`two_sample_test`, ``expected`` is the second sample's
    histogram scaled to the first's size.
    """

    p_value: float
    passed: bool
    statistic: float
    dof: int
    significance: float
    histogram: np.ndarray
    expected: np.ndarray
    domain: Domain
    messages: list[str] = field(default_factory=list)

    @property
    def message(self) -> str:
        """Everything the test noted, one line each."""
        return "\n".join(self.messages)

    def __bool__(self) -> bool:
        return self.passed

    def __repr__(self) -> str:
        verdict = "passed" if self.passed else "FAILED"
        return (f"Chi2Result({verdict}: p_value={self.p_value:.4g}, significance="
                f"{self.significance:.3g}, statistic={self.statistic:.6g}, dof={self.dof})")


def _verdict(stat: float, dof: int, significance: float, failures: list[str],
             messages: list[str]) -> tuple[float, bool]:
    if dof < 1:
        failures.append(f"only {dof} degrees of freedom: too few samples or cells")
    p_value = _chi2_sf(stat, dof) if dof >= 1 else float("nan")
    messages.append(f"chi^2 = {stat:.6g} with {dof} degrees of freedom, p-value = {p_value:.4g}")
    if failures:
        messages.extend(f"FAILED: {f}" for f in failures)
        return p_value, False
    if not np.isfinite(p_value) or p_value < significance:
        messages.append(f"REJECTED the null hypothesis: p-value {p_value:.4g} < "
                        f"significance level {significance:.4g}")
        return p_value, False
    messages.append(f"accepted: p-value {p_value:.4g} >= significance level {significance:.4g}")
    return p_value, True


# --------------------------------------------------------------------------
# Goodness of fit


def chi2_test(
    sample: Callable[[np.ndarray], Any],
    pdf: Callable[[np.ndarray], Any],
    domain: DomainLike,
    n: int = 1_000_000,
    sample_dim: int = 2,
    res: int | tuple[int, int] = 101,
    ires: int = 4,
    seed: int = 0,
    alpha: float = 0.01,
    test_count: int = 1,
) -> Chi2Result:
    """Pearson's chi-square test of ``sample`` against the density ``pdf``.

    Parameters
    ----------
    sample : callable
        Maps uniform numbers, an ndarray (n, sample_dim) float64 in [0, 1),
        to points: shape (n,) on an interval, (n, 2) on the plane, (n, 3)
        unit vectors on the sphere and hemisphere.
    pdf : callable
        Density of points (m, point_dim) → (m,), in the domain's measure
        (per steradian on the sphere, per unit area / length otherwise).
    domain : str, tuple or Domain
        "interval" ([0, 1]), "square" ([0, 1]^2), "disk" (unit disk),
        "plane" ([-1, 1]^2), "sphere", "hemisphere", an interval ``(a, b)``,
        a rectangle
        ``((x0, x1), (y0, y1))``, or a :class:`Domain`.
    n : int
        Number of samples.
    sample_dim : int
        Uniform numbers per sample.
    res : int or (columns, rows)
        Rows of the histogram (columns follow the domain's aspect); odd
        values keep cell edges off symmetry planes.
    ires : int >= 2
        Integration points per cell and axis; raise it for sharp densities.
    seed : int
        Seed of the uniform numbers (``mcsample.uniform``).
    alpha : float
        Significance level of the whole family of ``test_count`` tests
        (Šidák correction: each test runs at 1 - (1 - alpha)^(1/test_count)).
    test_count : int
        Number of tests run together.

    Returns
    -------
    Chi2Result
        ``.p_value``, ``.passed``, ``.statistic``, ``.dof``, ``.histogram``,
        ``.expected``, ``.message``. It fails, with the reason in
        ``.message``, on samples outside the domain or not finite, a negative
        or NaN density, a density integrating far from 1, or a sample in a
        cell of zero expected count.
    """
    dom = make_domain(domain)
    if int(ires) < 2:
        raise ValueError(f"ires = {ires}: must be >= 2")
    if int(n) < 1:
        raise ValueError(f"n = {n}: must be >= 1")
    significance = _sidak(alpha, test_count)
    shape = _grid_shape(dom, res)
    messages: list[str] = []
    failures: list[str] = []

    u = uniform(int(n), int(sample_dim), seed=seed)
    points = sample(u)
    observed = _histogram(dom, np.asarray(points), shape, failures, "sample")
    expected = _integrate_pdf(dom, pdf, shape, int(ires)) * n

    if not np.all(np.isfinite(expected)):
        failures.append("pdf returned NaN or infinite values")
    elif np.any(expected < 0):
        failures.append(f"pdf is negative (cell integral {expected.min() / n:.4g})")
    total = float(np.sum(expected[np.isfinite(expected)])) / n
    messages.append(f"pdf integrates to {total:.6f} over the domain; "
                    f"{int(observed.sum())} of {n} samples in the histogram")
    if not 0.9 <= total <= 1.1:
        failures.append(f"pdf integrates to {total:.4f}, not 1, over {dom!r} "
                        "(a wrong normalisation, or a lobe too sharp for ires)")
    zero_cells = (expected == 0) & (observed > 0)
    if np.any(zero_cells):
        failures.append(f"{int(observed[zero_cells].sum())} samples fell in cells where "
                        "the pdf integrates to 0")

    safe_expected = np.where(np.isfinite(expected), expected, 0.0)
    stat, dof, pooled_in, pooled_out = _pooled_chi2(observed.reshape(-1), safe_expected.reshape(-1))
    if pooled_in:
        messages.append(f"pooled {pooled_in} cells with expected count < 5 into {pooled_out}")
    p_value, passed = _verdict(stat, dof, significance, failures, messages)
    return Chi2Result(p_value, passed, stat, dof, significance, observed, expected, dom, messages)


def two_sample_test(
    a: Any,
    b: Any,
    domain: DomainLike,
    res: int | tuple[int, int] = 51,
    alpha: float = 0.01,
    test_count: int = 1,
) -> Chi2Result:
    """Chi-square test of homogeneity: were samples ``a`` and ``b`` drawn from
    the same distribution? For two samplers without a density (or whose
    densities you do not trust).

    Parameters
    ----------
    a, b : array_like
        Points, (n,) on an interval or (n, point_dim); sizes may differ.
    domain : str, tuple or Domain
        As for :func:`chi2_test`.
    res : int or (columns, rows)
        Histogram resolution; cells with few samples are pooled.
    alpha, test_count : as for :func:`chi2_test`.

    Returns
    -------
    Chi2Result
        ``histogram`` holds a's counts and ``expected`` b's counts scaled to
        a's size.
    """
    dom = make_domain(domain)
    significance = _sidak(alpha, test_count)
    shape = _grid_shape(dom, res)
    failures: list[str] = []
    messages: list[str] = []
    ha = _histogram(dom, np.asarray(a), shape, failures, "a").reshape(-1)
    hb = _histogram(dom, np.asarray(b), shape, failures, "b").reshape(-1)
    na, nb = ha.sum(), hb.sum()
    if na == 0 or nb == 0:
        raise ValueError("both samples need points inside the domain")
    # Pool cells (sorted by combined count) until each pooled cell expects
    # at least 5 points of each sample under the null hypothesis.
    order = np.argsort(ha + hb, kind="stable")
    ka, kb, terms, stat = 0.0, 0.0, 0, 0.0
    ca, cb = np.sqrt(nb / na), np.sqrt(na / nb)
    min_total = 5.0 * (na + nb) / min(na, nb)
    for i in order:
        ka += ha[i]
        kb += hb[i]
        if ka + kb >= min_total:
            stat += (ca * ka - cb * kb) ** 2 / (ka + kb)
            terms += 1
            ka = kb = 0.0
    dof = terms - 1
    messages.append(f"{int(na)} and {int(nb)} samples in {terms} pooled cells")
    p_value, passed = _verdict(stat, dof, significance, failures, messages)
    expected = (hb * (na / nb)).reshape(shape[1], shape[0])
    return Chi2Result(p_value, passed, stat, dof, significance,
                      ha.reshape(shape[1], shape[0]), expected, dom, messages)


# --------------------------------------------------------------------------
# Images


def _pair(a: Any, b: Any) -> tuple[np.ndarray, np.ndarray]:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"images must have the same shape, got {a.shape} and {b.shape}")
    return a, b


def luminance(rgb: Any) -> np.ndarray:
    """Rec. 709 luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of linear RGB
    values, (..., 3) → (...), float64."""
    x = np.asarray(rgb, dtype=np.float64)
    if x.shape[-1:] != (3,):
        raise ValueError(f"luminance needs RGB values on the last axis, got shape {x.shape}")
    return x @ np.array([0.2126, 0.7152, 0.0722])


def mse(image: Any, reference: Any) -> float:
    """Mean squared error over all pixels and channels."""
    a, b = _pair(image, reference)
    return float(np.mean((a - b) ** 2))


def relmse(image: Any, reference: Any, eps: float = 1e-2) -> float:
    """Relative MSE, mean of (image - reference)^2 / (reference^2 + eps),
    over all pixels and channels (``eps`` keeps dark pixels from dominating)."""
    a, b = _pair(image, reference)
    return float(np.mean((a - b) ** 2 / (b * b + eps)))


@dataclass
class ImageZTestResult:
    """Outcome of :func:`image_ztest`: per-pixel z-scores and their summary."""

    z: np.ndarray
    mean: float
    variance: float
    outliers: int
    mean_difference_z: float
    passed: bool
    messages: list[str] = field(default_factory=list)

    @property
    def message(self) -> str:
        return "\n".join(self.messages)

    def __bool__(self) -> bool:
        return self.passed

    def __repr__(self) -> str:
        verdict = "passed" if self.passed else "FAILED"
        return (f"ImageZTestResult({verdict}: mean={self.mean:.4g}, variance={self.variance:.4g},"
                f" outliers={self.outliers}, mean_difference_z={self.mean_difference_z:.3g})")


def image_ztest(a: Any, var_a: Any, b: Any, var_b: Any, outlier_z: float = 5.0,
                max_outliers: int | None = None) -> ImageZTestResult:
    """Per-pixel z-test of two independent estimates of the same image.

    z = (a - b) / sqrt(var_a + var_b) per pixel and channel, where the
    variances are those of the estimates (of the mean, not of one sample).
    If the two agree, z is close to N(0, 1). Passes when the mean of z lies
    within 5 standard errors of 0 (plus 0.05 slack for non-normal tails), its
    variance in [0.7, 1.4], no more than ``max_outliers`` values have
    |z| > ``outlier_z`` (default max(3, 1e-4 of the values)), and the
    whole-image means agree within 3 standard errors.

    Entries where both variances are 0 count as z = 0 when a == b, else as
    outliers.
    """
    a, b = _pair(a, b)
    va, vb = _pair(var_a, var_b)
    if a.shape != va.shape:
        raise ValueError(f"variances must have the images' shape {a.shape}, got {va.shape}")
    for name, arr in (("a", a), ("b", b), ("var_a", va), ("var_b", vb)):
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} has NaN or infinite values")
    if np.any(va < 0) or np.any(vb < 0):
        raise ValueError("variances must be >= 0")
    var = va + vb
    diff = a - b
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(var > 0, diff / np.sqrt(np.where(var > 0, var, 1.0)),
                     np.where(diff == 0, 0.0, np.inf))
    count = z.size
    if max_outliers is None:
        max_outliers = max(3, int(1e-4 * count))
    finite = np.isfinite(z)
    outliers = int(np.count_nonzero(~finite | (np.abs(z) > outlier_z)))
    zf = z[finite]
    mean, variance = float(zf.mean()), float(zf.var())
    se_total = float(np.sqrt(var.sum())) / count
    mean_diff = float(diff.mean())
    mean_difference_z = mean_diff / se_total if se_total > 0 else (0.0 if mean_diff == 0 else np.inf)
    messages = [f"z: mean {mean:.4g}, variance {variance:.4g}, {outliers} of {count} beyond "
                f"|z| > {outlier_z}; whole-image mean difference {mean_difference_z:.3g} SE"]
    checks = {
        "mean of z far from 0": abs(mean) > 5.0 / np.sqrt(max(zf.size, 1)) + 0.05,
        "variance of z outside [0.7, 1.4]": not 0.7 <= variance <= 1.4,
        f"more than {max_outliers} outliers": outliers > max_outliers,
        "whole-image means differ by more than 3 SE": abs(mean_difference_z) > 3.0,
    }
    failed = [k for k, bad in checks.items() if bad]
    messages.extend(f"FAILED: {k}" for k in failed)
    return ImageZTestResult(z, mean, variance, outliers, mean_difference_z, not failed, messages)


def render_ztest(image: Any, reference: Any, noise_free: float = 1e-4, rtol: float = 1e-3,
                 **kwargs: Any) -> ImageZTestResult:
    """:func:`image_ztest` of two renders' luminances (objects with
    ``.luminance`` and ``.luminance_variance`` (H, W), as
    :class:`mcsample.RenderResult` and :func:`mcsample.mitsuba.render_reference`
    return).

    Pixels whose relative standard error is below ``noise_free`` on both
    sides (e.g. directly seen sky, smooth over a pixel) are deterministic up
    to float32 rounding, which then dominates a variance estimated as
    E[Y²] − E[Y]²: they are compared with relative tolerance ``rtol``
    instead of entering the z-test (the result's ``z`` is 0 there).
    ``kwargs`` go to :func:`image_ztest`.
    """
    a, b = (np.asarray(x.luminance, dtype=np.float64) for x in (image, reference))
    va, vb = (np.asarray(x.luminance_variance, dtype=np.float64) for x in (image, reference))
    if a.shape != b.shape:
        raise ValueError(f"image shape {a.shape} differs from reference shape {b.shape}")
    scale = np.maximum(np.abs(b), 1e-6)
    noisy = (np.sqrt(va) > noise_free * scale) | (np.sqrt(vb) > noise_free * scale)
    if not noisy.any():
        raise ValueError("no pixel of either render has noise: nothing to z-test")
    t = image_ztest(a[noisy], va[noisy], b[noisy], vb[noisy], **kwargs)
    z = np.zeros(a.shape)
    z[noisy] = t.z
    t.z = z
    quiet = int(np.count_nonzero(~noisy))
    t.messages.insert(1, f"{quiet} noise-free pixels compared with rtol {rtol:g}")
    if not np.allclose(a[~noisy], b[~noisy], rtol=rtol, atol=1e-6):
        t.passed = False
        t.messages.append(f"FAILED: noise-free pixels differ by more than rtol {rtol:g}")
    return t
