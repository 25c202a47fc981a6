"""Domains for the chi-square tests: each maps target points to a 2D
parameter box whose boundary is the domain's boundary (so no cell straddles
an edge of the support) and gives the Jacobian from the box's measure to the
target measure (per steradian on the sphere, per unit area on the plane, per
unit length on an interval)."""

from __future__ import annotations

from typing import Any, Callable, Sequence, Union

import numpy as np


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


class ConeDomain(SphericalDomain):
    """The directions within angle theta_max of +z (cos theta >=
    ``cos_max``), parameterised by (phi, cos theta) ∈ [-pi, pi] ×
    [cos_max, 1] (area-preserving); densities per steradian.

    For samplers of a small solid angle, such as a light seen from a point:
    rotate the samples so that +z points into the cone (e.g. with
    ``mcsample.Frame``) and choose ``cos_max`` so the cone holds every
    sample; the histogram's cells then all lie where the samples go.
    """

    point_dim = 3

    def __init__(self, cos_max: float):
        if not -1.0 <= cos_max < 1.0:
            raise ValueError(f"cos_max = {cos_max}: must lie in [-1, 1)")
        super().__init__()
        self.cos_max = float(cos_max)
        self.bounds = ((-np.pi, np.pi), (self.cos_max, 1.0))
        self.aspect = 1.0

    def __repr__(self) -> str:
        return f"ConeDomain(cos_max={self.cos_max:.6g})"


class EnvMapDomain(Domain):
    """The sphere in the coordinates of an environment map's sampling table,
    where its piecewise density is constant on cells: lat-long, Mitsuba's
    (u, v); angular, polar coordinates around the probe's +Z, (psi, rho) =
    (atan2(y, x) / 2 pi, acos(z) / pi); cube, (u, face + v). Densities per
    steradian.

    ``cells`` is a histogram resolution (rows, columns) whose cells each lie
    in one cell of the table (lat-long: half-texel columns, rows between
    texel rows; angular: 2W sectors x W rings; cube: half-texel cells), so
    that the
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
            self.cells: tuple[int, int] = (12 * r, 2 * r)
        elif self.mapping == "angular":
            self.bounds = ((0.0, 1.0), (0.0, 1.0))
            self.cells = (max(shape[1], 2), max(2 * shape[1], 4))
        else:
            h, w = shape[:2]
            self.bounds = ((0.0, 1.0), (0.0, 1.0))
            self.cells = (h - 1, 2 * w)
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
