"""Image comparison: :func:`mse`, :func:`relmse`, :func:`image_ztest`, and
:func:`render_ztest` for two renders."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..results import Result


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


@dataclass(repr=False)
class ZTestResult(Result):
    """Outcome of :func:`image_ztest` and :func:`render_ztest`.

    Attributes
    ----------
    passed : bool
        Whether the two estimates agree.
    mean_z : float
        Difference of the whole-image means, in standard errors.
    block_z : ndarray (rows, columns)
        The same for each block of ``block × block`` pixels (NaN for a block
        without noisy pixels).
    threshold : float
        The largest ``|z|`` allowed of the whole image and of any block.
    z : ndarray
        Per-pixel z-scores, for maps (0 on noise-free pixels); not tested.
    relative_difference : float
        (mean of image) / (mean of reference) − 1.
    relative_se : float
        The standard error of the whole-image difference over the
        reference's mean: the test finds a bias everywhere of about
        ``(threshold + 2) * relative_se`` or more (with 98 % power).
    messages : list of str
        What the test found, one line each (also as ``.message``).
    """

    _hidden = ("z", "messages")

    passed: bool
    mean_z: float
    block_z: np.ndarray
    threshold: float
    z: np.ndarray
    relative_difference: float
    relative_se: float
    messages: list[str] = field(default_factory=list)

    @property
    def message(self) -> str:
        """Everything the test noted, one line each."""
        return "\n".join(self.messages)

    def __bool__(self) -> bool:
        return self.passed


def _block_sums(x: np.ndarray, block: int) -> np.ndarray:
    """Sums of ``x`` (H, W) over blocks of ``block × block`` pixels (the
    last row and column of blocks may be smaller)."""
    h, w = x.shape
    rows, cols = -(-h // block), -(-w // block)
    padded = np.zeros((rows * block, cols * block))
    padded[:h, :w] = x
    return padded.reshape(rows, block, cols, block).sum(axis=(1, 3))


def _as_image(x: Any, name: str) -> np.ndarray:
    """``x`` as a float64 (H, W) array; 1D data is one row."""
    a = np.asarray(x, dtype=np.float64)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2:
        raise ValueError(f"{name} must be an image (H, W) or a 1D array of values, got shape "
                         f"{a.shape} (compare luminances or one channel)")
    return a


def _region_variance(var: np.ndarray, runs: np.ndarray | None, mask: np.ndarray,
                     block: int) -> tuple[float, np.ndarray, float]:
    """The variance of one side's whole-image sum and of each block's sum,
    and its degrees of freedom: from the pixel variances (independent
    pixels; exact, infinite degrees) or, given ``runs`` (R, H, W) of
    independent renders whose mean is the image, from the spread of the
    runs' sums over R (right also when neighbouring pixels share samples,
    as under a splatting filter; R − 1 degrees)."""
    if runs is None:
        return float(np.where(mask, var, 0.0).sum()), _block_sums(np.where(mask, var, 0.0),
                                                                   block), np.inf
    r = np.where(mask, runs, 0.0)
    n = r.shape[0]
    whole = float(r.sum(axis=(1, 2)).var(ddof=1) / n)
    blocks = np.stack([_block_sums(x, block) for x in r]).var(axis=0, ddof=1) / n
    return whole, blocks, float(n - 1)


def _normal_equivalent(z: np.ndarray, va: Any, vb: Any, dof_a: float,
                       dof_b: float) -> np.ndarray:
    """``z`` of a difference whose variance ``va + vb`` is estimated with
    ``dof_a`` and ``dof_b`` degrees of freedom, mapped to the normal z of
    the same tail probability (Student's t with Welch–Satterthwaite's
    degrees; unchanged when both are exact)."""
    if np.isinf(dof_a) and np.isinf(dof_b):
        return z
    from scipy.special import ndtri
    from scipy.stats import t as student

    va, vb = np.asarray(va, dtype=np.float64), np.asarray(vb, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        dof = (va + vb) ** 2 / (va**2 / dof_a + vb**2 / dof_b)
        return np.sign(z) * -ndtri(student.sf(np.abs(z), np.where(np.isfinite(dof), dof,
                                                                     1e9)))


def image_ztest(a: Any, var_a: Any, b: Any, var_b: Any, *, block: int = 8,
                alpha: float = 1e-3, tested: Any = None, runs_a: Any = None,
                runs_b: Any = None) -> ZTestResult:
    """Whether two independent estimates of the same image agree, by z-tests
    of the whole image and of blocks of pixels.

    ``a`` and ``b`` are (H, W) images (or 1D arrays of pixel values, taken
    as one row), ``var_a`` and ``var_b`` the variances of each pixel's
    estimate (of the mean, not of one sample). The difference of the two
    means over a region, divided by its standard error (the square root of
    the sum of both sides' pixel variances over the region's pixel count
    squared), is close to N(0, 1) when both are unbiased estimates of the
    same image. The test takes that z of the whole image (power against a
    bias everywhere: a 2 % bias is found when the image mean's relative
    standard error is below about 0.35 %) and of each block of ``block ×
    block`` pixels (power against a bias in one part of the image). Blocks
    pool many samples, so their z is close to normal even where one pixel's
    is heavy-tailed (a few samples of a bright, rarely hit light). The test
    fails when any of these ``1 + blocks`` z-scores exceeds the two-sided
    threshold of significance ``alpha`` shared among them (Šidák).

    ``tested`` (a boolean image) limits the z-tests to some pixels (the
    others count as equal); by default all.

    ``runs_a`` / ``runs_b`` (R, H, W): independent renders whose mean is
    ``a`` / ``b``, for an image whose neighbouring pixels are correlated
    (Mitsuba's splatting filters): the variances of the whole image and of
    each block then come from the spread of the runs' sums (R − 1 degrees
    of freedom; each z is converted to the normal z of the same Student-t
    tail probability, Welch–Satterthwaite's degrees), not from the pixel
    variances, whose sum ignores the covariances.
    """
    from scipy.special import ndtri

    a, b = _as_image(a, "a"), _as_image(b, "b")
    va, vb = _as_image(var_a, "var_a"), _as_image(var_b, "var_b")
    if not a.shape == b.shape == va.shape == vb.shape:
        raise ValueError(f"images and variances must have one shape, got {a.shape}, {b.shape}, "
                         f"{va.shape} and {vb.shape}")
    if int(block) < 1:
        raise ValueError(f"block = {block}: must be >= 1")
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha = {alpha}: must lie in (0, 1)")
    mask = np.ones(a.shape, bool) if tested is None else _as_image(tested, "tested") > 0
    for name, arr in (("a", a), ("b", b)):
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} has NaN or infinite values")
    for name, arr in (("var_a", va), ("var_b", vb)):
        if not np.all(arr[mask] >= 0):
            raise ValueError(f"{name} must be >= 0")
        if not np.all(np.isfinite(arr[mask])):
            raise ValueError(f"{name} is infinite (a one-sample pixel has no variance: "
                             "render with spp >= 2)")
    runs = []
    for name, r, image in (("runs_a", runs_a, a), ("runs_b", runs_b, b)):
        if r is not None:
            r = np.asarray(r, dtype=np.float64)
            if r.ndim != 3 or r.shape[1:] != image.shape or r.shape[0] < 2:
                raise ValueError(f"{name} must be (R, H, W) with R >= 2 renders of the image's "
                                 f"shape {image.shape}, got {r.shape}")
            if not np.all(np.isfinite(r)):
                raise ValueError(f"{name} has NaN or infinite values")
        runs.append(r)
    diff = np.where(mask, a - b, 0.0)
    var = np.where(mask, va + vb, 0.0)
    if not var.sum() > 0:
        raise ValueError("no tested pixel has noise: nothing to z-test")
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(var > 0, diff / np.sqrt(var), 0.0)
    block = int(block)
    (whole_a, blocks_a, dof_a), (whole_b, blocks_b, dof_b) = (
        _region_variance(v, r, mask, block) for v, r in ((va, runs[0]), (vb, runs[1])))
    mean_z = float(_normal_equivalent(np.array(diff.sum() / np.sqrt(whole_a + whole_b)),
                                      whole_a, whole_b, dof_a, dof_b))
    block_diff, block_var = _block_sums(diff, block), blocks_a + blocks_b
    with np.errstate(divide="ignore", invalid="ignore"):
        block_z = np.where(block_var > 0, block_diff / np.sqrt(block_var), np.nan)
    block_z = _normal_equivalent(block_z, blocks_a, blocks_b, dof_a, dof_b)
    tests = 1 + int(np.count_nonzero(np.isfinite(block_z)))
    per_test = 1.0 - (1.0 - alpha) ** (1.0 / tests)
    threshold = float(-ndtri(per_test / 2))
    worst = float(np.nanmax(np.abs(block_z)))
    ref_mean = float(b.mean())
    relative = float(a.mean() / ref_mean - 1.0) if ref_mean != 0 else float("nan")
    relative_se = (float(np.sqrt(whole_a + whole_b) / b.size / abs(ref_mean)) if ref_mean
                   else float("nan"))
    messages = [
        f"whole image: z = {mean_z:.3g} (means {a.mean():.6g} and {ref_mean:.6g}, "
        f"relative difference {relative:+.3%} ± {relative_se:.3%})",
        f"blocks of {block}x{block}: largest |z| = {worst:.3g} of {tests - 1}; "
        f"threshold {threshold:.3g} (alpha {alpha:g} over {tests} z-tests)",
    ]
    failures = []
    if abs(mean_z) > threshold:
        failures.append(f"the whole-image means differ by {mean_z:.3g} standard errors")
    if worst > threshold:
        i, j = np.unravel_index(np.nanargmax(np.abs(block_z)), block_z.shape)
        failures.append(f"block ({i}, {j}) (rows {i * block}.., columns {j * block}..) "
                        f"differs by {block_z[i, j]:.3g} standard errors")
    messages.extend(f"FAILED: {f}" for f in failures)
    return ZTestResult(not failures, mean_z, block_z, threshold, z, relative, relative_se,
                       messages)


def render_ztest(image: Any, reference: Any, *, block: int = 8, alpha: float = 1e-3,
                 noise_free: float = 1e-4, rtol: float = 1e-3) -> ZTestResult:
    """Whether two independent renders of one scene agree: :func:`image_ztest`
    of their luminances.

    ``image`` and ``reference`` are objects with ``.luminance`` and
    ``.luminance_variance`` (H, W), the variance of each pixel's mean, as
    :class:`mcsample.RenderResult` and
    :func:`mcsample.mitsuba.render_reference` return.

    A render with ``.runs`` (a Mitsuba reference of a splatting filter,
    :func:`mcsample.mitsuba.render_reference`) takes its region variances
    from them (see :func:`image_ztest`'s ``runs_a``).

    Pixels whose relative standard error is below ``noise_free`` on both
    sides (e.g. directly seen sky, smooth over a pixel) are deterministic up
    to float32 rounding, which then dominates a variance estimated as
    E[Y²] − E[Y]²: they are compared with relative tolerance ``rtol``
    instead of entering the z-tests.
    """
    a, b = (np.asarray(x.luminance, dtype=np.float64) for x in (image, reference))
    runs = [getattr(x, "runs", None) for x in (image, reference)]
    va, vb = (np.asarray(x.luminance_variance, dtype=np.float64) for x in (image, reference))
    if a.shape != b.shape:
        raise ValueError(f"image shape {a.shape} differs from reference shape {b.shape}")
    scale = np.maximum(np.abs(b), 1e-6)
    with np.errstate(invalid="ignore"):
        noisy = (np.sqrt(va) > noise_free * scale) | (np.sqrt(vb) > noise_free * scale)
    if not noisy.any():
        raise ValueError("no pixel of either render has noise: nothing to z-test")
    t = image_ztest(a, va, b, vb, block=block, alpha=alpha, tested=noisy, runs_a=runs[0],
                    runs_b=runs[1])
    quiet = int(np.count_nonzero(~noisy))
    t.messages.insert(2, f"{quiet} noise-free pixels compared with rtol {rtol:g}")
    if not np.allclose(a[~noisy], b[~noisy], rtol=rtol, atol=1e-6):
        t.passed = False
        t.messages.append(f"FAILED: noise-free pixels differ by more than rtol {rtol:g}")
    return t
