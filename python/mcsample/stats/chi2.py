"""Goodness of fit: :func:`chi2_test` of a sampler against its density, and
:func:`two_sample_test` of two samplers."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .._core import uniform
from ..results import Result
from .domains import Domain, DomainLike, make_domain


def _grid_shape(domain: Domain, res: int | tuple[int, int]) -> tuple[int, int]:
    """(columns, rows) of the histogram from ``res``: rows, or (rows,
    columns) as numpy's shapes."""
    if isinstance(res, tuple):
        ny, nx = res
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


def _jittered_cells(domain: Domain, pdf: Callable[[np.ndarray], Any], shape: tuple[int, int],
                    cells: np.ndarray, ires: int, passes: int,
                    rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The integral of `pdf` over the flat cell indices `cells` (row-major,
    (rows, columns) grid) by stratified Monte Carlo, one uniform point in
    each of `ires × ires` strata of a cell per pass: the mean of `passes`
    passes and the variance of that mean (from their spread)."""
    nx, ny = shape
    (x0, x1), (y0, y1) = domain.bounds
    one_d = domain.aspect is None
    hx, hy = (x1 - x0) / nx, (y1 - y0) / ny
    iy, ix = np.divmod(cells, nx)
    k = int(ires)
    strata_y = 1 if one_d else k
    sx = np.tile(np.arange(k), strata_y)
    sy = np.repeat(np.arange(strata_y), k)
    estimates = np.empty((passes, cells.size))
    for p in range(passes):
        jitter = rng.random((cells.size, sx.size, 2))
        px = x0 + (ix[:, None] + (sx[None, :] + jitter[..., 0]) / k) * hx
        py = (np.full(px.shape, 0.5 * (y0 + y1)) if one_d
              else y0 + (iy[:, None] + (sy[None, :] + jitter[..., 1]) / k) * hy)
        xy = np.stack([px.reshape(-1), py.reshape(-1)], axis=1)
        values = np.asarray(pdf(domain.from_param(xy)), dtype=np.float64).reshape(-1)
        if values.shape[0] != xy.shape[0]:
            raise ValueError(f"pdf must return one value per point: {xy.shape[0]} points "
                             f"gave shape {np.shape(values)}")
        values = (values * domain.jacobian(xy)).reshape(cells.size, sx.size)
        estimates[p] = values.mean(axis=1) * hx * (1.0 if one_d else hy)
    return estimates.mean(axis=0), estimates.var(axis=0, ddof=1) / passes


def _jittered_pdf_integral(domain: Domain, pdf: Callable[[np.ndarray], Any],
                           shape: tuple[int, int], ires: int, n: int,
                           observed: np.ndarray,
                           seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Integral of `pdf` over each cell (rows, columns) by stratified Monte
    Carlo ([`_jittered_cells`], 16 passes), an unbiased estimate even where
    the density jumps inside a cell. Cells where the estimate's variance is
    not small next to the Poisson variance of the counts of `n` samples
    (those a jump crosses), and cells whose `observed` count lies more than
    4 standard deviations from the estimate (a sliver of high density that
    few or no points met, so that the spread of the passes underrates the
    error), are estimated again, independently (which keeps the estimate
    unbiased whatever chose the cell), with twice the strata per axis, up
    to five times. Returns the estimates and their variances."""
    nx, ny = shape
    counts = observed.reshape(-1)
    rng = np.random.default_rng(seed)
    cells = np.arange(nx * ny)
    mean, var = _jittered_cells(domain, pdf, shape, cells, ires, 16, rng)
    k = int(ires)
    for _ in range(5):
        # Var of the expected count n·mean next to the count's own, n·mean.
        expected = n * mean
        rough = np.flatnonzero((n * var > 0.02 * np.maximum(mean, 1.0 / n))
                               | ((mean == 0) & (counts > 0))
                               | ((counts - expected) ** 2 > 16 * (expected + n * n * var + 1)))
        if rough.size == 0:
            break
        k *= 2
        mean[rough], var[rough] = _jittered_cells(domain, pdf, shape, rough, k, 16, rng)
    return mean.reshape(ny, nx), var.reshape(ny, nx)


def _pooled_chi2(observed: np.ndarray, expected: np.ndarray,
                 expected_var: np.ndarray | None = None,
                 threshold: float = 5.0) -> tuple[float, int, int, int]:
    """Pearson's statistic over cells sorted by expected count, pooling
    consecutive cells below `threshold` until their pooled expectation passes
    it (leftover cells are dropped, as Mitsuba does). With `expected_var`
    (the variance of an estimated expectation), each term's denominator is
    the variance of observed − expected, `expected + expected_var`. Returns
    (statistic, dof, cells pooled, pooled cells made)."""
    if expected_var is None:
        expected_var = np.zeros_like(expected)
    order = np.argsort(expected, kind="stable")
    obs, exp, var = observed[order], expected[order], expected_var[order]
    high = exp >= threshold
    stat = float(np.sum((obs[high] - exp[high]) ** 2 / (exp[high] + var[high])))
    terms = int(np.count_nonzero(high))
    low = ~high & ((obs != 0) | (exp != 0))
    pooled_obs = pooled_exp = pooled_var = 0.0
    pooled_in = pooled_out = 0
    for o, e, v in zip(obs[low], exp[low], var[low]):
        pooled_obs += o
        pooled_exp += e
        pooled_var += v
        pooled_in += 1
        if pooled_exp > threshold:
            stat += (pooled_obs - pooled_exp) ** 2 / (pooled_exp + pooled_var)
            pooled_obs = pooled_exp = pooled_var = 0.0
            pooled_out += 1
            terms += 1
    return stat, terms - 1, pooled_in, pooled_out


def _block_sums(x: np.ndarray, block: int) -> np.ndarray:
    """Sums of `x` (rows, columns) over blocks of `block` cells along each
    axis longer than one cell (the last blocks may be smaller)."""
    by = block if x.shape[0] > 1 else 1
    rows, cols = -(-x.shape[0] // by), -(-x.shape[1] // block)
    padded = np.zeros((rows * by, cols * block))
    padded[:x.shape[0], :x.shape[1]] = x
    return padded.reshape(rows, by, cols, block).sum(axis=(1, 3))


#: Cells merged per axis at each level of the multi-resolution test.
LEVELS = (1, 8, 32)


def _multiresolution_chi2(observed: np.ndarray, expected: np.ndarray, expected_var: np.ndarray,
                          messages: list[str]) -> tuple[float, int, float]:
    """Pearson's test on the histogram and on coarser ones made by merging
    8×8 and 32×32 cells (as long as 8 merged cells or more remain): a fine
    grid finds a narrow error, a coarse one a small error spread wide (a
    density 2 % off over half the domain adds (0.02)² n / 2 to the
    statistic at any resolution, against a spread of √(2 dof): fewer cells,
    more power). Returns the finest level's statistic and degrees of
    freedom, and the smallest p-value over the levels, Šidák-adjusted for
    their number."""
    results = []
    for block in LEVELS:
        if block > 1 and _block_sums(np.ones(observed.shape), block).size < 8:
            break
        stat, dof, pooled_in, pooled_out = _pooled_chi2(
            _block_sums(observed, block).reshape(-1), _block_sums(expected, block).reshape(-1),
            _block_sums(expected_var, block).reshape(-1))
        p = _chi2_sf(stat, dof) if dof >= 1 else float("nan")
        results.append((stat, dof, p))
        pooled = f", pooled {pooled_in} cells with expected count < 5 into {pooled_out}" \
            if pooled_in else ""
        messages.append(f"cells merged {block}x{block}: chi^2 = {stat:.6g} with {dof} degrees "
                        f"of freedom, p-value = {p:.4g}{pooled}")
    stat, dof, _ = results[0]
    p_values = [p for _, d, p in results if d >= 1]
    if not p_values:
        return stat, dof, float("nan")
    p_min = min(p_values)
    return stat, dof, float(1.0 - (1.0 - p_min) ** len(p_values))


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


@dataclass(repr=False)
class Chi2Result(Result):
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

    _hidden = ("histogram", "expected", "domain", "messages")

    @property
    def message(self) -> str:
        """Everything the test noted, one line each."""
        return "\n".join(self.messages)

    def __bool__(self) -> bool:
        return self.passed


def _verdict(stat: float, dof: int, p_value: float, significance: float, failures: list[str],
             messages: list[str]) -> tuple[float, bool]:
    if dof < 1:
        failures.append(f"only {dof} degrees of freedom: too few samples or cells")
    messages.append(f"p-value = {p_value:.4g}")
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
    integration: str = "trapezoid",
) -> Chi2Result:
    """Pearson's chi-square test of ``sample`` against the density ``pdf``.

    The test runs at three resolutions: the histogram of ``res`` and two
    made from it by merging 8×8 and 32×32 cells (while 8 or more remain);
    its p-value is the smallest of theirs, Šidák-adjusted. The coarse levels
    find what the fine one cannot at a given sample count: with 10⁶
    samples, a density 2 % off on a fifth of the domain is caught in 20 of
    20 seeds, where the fine histogram alone catches it once.

    Parameters
    ----------
    sample : callable
        Maps uniform numbers, an ndarray (n, sample_dim) float64 in [0, 1),
        to points: shape (n,) on an interval, (n, 2) on the plane, (n, 3)
        unit vectors on the sphere and hemisphere. It may return fewer
        points than numbers (dropping samples that carry nothing); ``pdf``
        then integrates to the fraction kept.
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
    res : int or (rows, columns)
        Rows of the histogram (columns follow the domain's aspect), or
        both, as numpy's shapes; odd values keep cell edges off symmetry
        planes.
    ires : int >= 2
        Integration points per cell and axis; raise it for sharp densities.
    seed : int
        Seed of the uniform numbers (``mcsample.uniform``).
    alpha : float
        Significance level of the whole family of ``test_count`` tests
        (Šidák correction: each test runs at 1 - (1 - alpha)^(1/test_count)).
    test_count : int
        Number of tests run together.
    integration : "trapezoid" or "jittered"
        How each cell's expected count is found. "trapezoid" (Mitsuba's):
        the trapezoid rule on ``ires × ires`` points per cell, exact for a
        smooth density as ``ires`` grows, but biased in a cell that a jump
        of the density crosses (the edge of a light seen from a point),
        where it can reject a right sampler. "jittered": stratified Monte
        Carlo, one random point in each of ``ires × ires`` strata per cell,
        in 16 passes, and again with finer strata in the cells where a jump
        leaves the estimate noisy next to the counts: unbiased for any
        density. What variance the estimate keeps (from the spread of the
        passes) is added to each cell's expected variance.

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
    if integration == "trapezoid":
        expected, expected_var = _integrate_pdf(dom, pdf, shape, int(ires)) * n, None
    elif integration == "jittered":
        integral, integral_var = _jittered_pdf_integral(dom, pdf, shape, int(ires), int(n),
                                                          observed, seed)
        expected, expected_var = integral * n, integral_var * float(n) ** 2
    else:
        raise ValueError(f"integration = {integration!r}: must be 'trapezoid' or 'jittered'")

    if not np.all(np.isfinite(expected)):
        failures.append("pdf returned NaN or infinite values")
    elif np.any(expected < 0):
        failures.append(f"pdf is negative (cell integral {expected.min() / n:.4g})")
    total = float(np.sum(expected[np.isfinite(expected)])) / n
    messages.append(f"pdf integrates to {total:.6f} over the domain; "
                    f"{int(observed.sum())} of {n} samples in the histogram")
    # A sampler may return fewer points than it was given numbers (samples
    # that carry nothing, such as the back of a one-sided light): its
    # density then integrates to less than 1, and the counts test it.
    returned = len(np.asarray(points))
    if total > 1.1 or (total < 0.9 and returned == n):
        failures.append(f"pdf integrates to {total:.4f}, not 1, over {dom!r} "
                        "(a wrong normalisation, or a lobe too sharp for ires)")
    # (A jittered estimate is 0 in an edge cell whose points all missed the
    # support: its samples are pooled and tested instead.)
    zero_cells = (expected == 0) & (observed > 0)
    if integration == "trapezoid" and np.any(zero_cells):
        failures.append(f"{int(observed[zero_cells].sum())} samples fell in cells where "
                        "the pdf integrates to 0")

    safe_expected = np.where(np.isfinite(expected), expected, 0.0)
    safe_var = np.zeros_like(safe_expected) if expected_var is None else np.nan_to_num(expected_var)
    stat, dof, p_value = _multiresolution_chi2(observed, safe_expected, safe_var, messages)
    p_value, passed = _verdict(stat, dof, p_value, significance, failures, messages)
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
    res : int or (rows, columns)
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
    p_value = _chi2_sf(stat, dof) if dof >= 1 else float("nan")
    messages.append(f"{int(na)} and {int(nb)} samples in {terms} pooled cells: "
                    f"chi^2 = {stat:.6g} with {dof} degrees of freedom")
    p_value, passed = _verdict(stat, dof, p_value, significance, failures, messages)
    expected = (hb * (na / nb)).reshape(shape[1], shape[0])
    return Chi2Result(p_value, passed, stat, dof, significance,
                      ha.reshape(shape[1], shape[0]), expected, dom, messages)
