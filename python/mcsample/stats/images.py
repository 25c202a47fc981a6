"""Image comparison: :func:`mse`, :func:`relmse`, :func:`image_ztest`, and
:func:`render_ztest` for two renders."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


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


@dataclass
class RenderZTestResult:
    """Outcome of :func:`render_ztest`.

    Attributes
    ----------
    passed : bool
        Whether the two renders agree (see :func:`render_ztest`).
    mean_z : float
        Difference of the whole-image mean luminances, in standard errors.
    block_z : ndarray (rows, columns)
        The same for each block of ``block × block`` pixels (NaN for a block
        without noisy pixels).
    threshold : float
        The largest ``|z|`` allowed of the whole image and of any block.
    z : ndarray (H, W)
        Per-pixel z-scores, for maps (0 on noise-free pixels); not tested.
    relative_difference : float
        (mean of image) / (mean of reference) − 1.
    relative_se : float
        The standard error of the whole-image difference over the
        reference's mean: the test finds a bias everywhere of about
        ``(threshold + 2) * relative_se`` or more (with 98 % power).
    """

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

    def __repr__(self) -> str:
        verdict = "passed" if self.passed else "FAILED"
        worst = np.nanmax(np.abs(self.block_z)) if np.isfinite(self.block_z).any() else 0.0
        return (f"RenderZTestResult({verdict}: mean_z={self.mean_z:.3g}, max |block z|="
                f"{worst:.3g}, threshold={self.threshold:.3g}, relative_difference="
                f"{self.relative_difference:.3g})")


def _block_sums(x: np.ndarray, block: int) -> np.ndarray:
    """Sums of ``x`` (H, W) over blocks of ``block × block`` pixels (the
    last row and column of blocks may be smaller)."""
    h, w = x.shape
    rows, cols = -(-h // block), -(-w // block)
    padded = np.zeros((rows * block, cols * block))
    padded[:h, :w] = x
    return padded.reshape(rows, block, cols, block).sum(axis=(1, 3))


def render_ztest(image: Any, reference: Any, block: int = 8, alpha: float = 1e-3,
                 noise_free: float = 1e-4, rtol: float = 1e-3) -> RenderZTestResult:
    """Whether two independent renders of one scene agree, by z-tests of
    their luminances over the whole image and over blocks of pixels.

    ``image`` and ``reference`` are objects with ``.luminance`` and
    ``.luminance_variance`` (H, W), the variance of each pixel's mean, as
    :class:`mcsample.RenderResult` and
    :func:`mcsample.mitsuba.render_reference` return.

    The difference of the two means over a region, divided by its standard
    error (the square root of the sum of both sides' pixel variances over
    the region's pixel count squared), is close to N(0, 1) when both
    renders are unbiased estimates of the same image. The test takes that
    z of the whole image (power against a bias everywhere: a 2 % bias is
    found when the image mean's relative standard error is below about
    0.35 %) and of each block of ``block × block`` pixels (power against a
    bias in one part of the image). Blocks pool many samples, so their z
    is close to normal even where one pixel's is heavy-tailed (a few
    samples of a bright, rarely hit light). The test fails when any of
    these ``1 + blocks`` z-scores exceeds the two-sided threshold of
    significance ``alpha`` shared among them (Šidák).

    Pixels whose relative standard error is below ``noise_free`` on both
    sides (e.g. directly seen sky, smooth over a pixel) are deterministic up
    to float32 rounding, which then dominates a variance estimated as
    E[Y²] − E[Y]²: they are compared with relative tolerance ``rtol``
    instead of entering the z-tests.
    """
    from scipy.special import ndtri

    a, b = (np.asarray(x.luminance, dtype=np.float64) for x in (image, reference))
    va, vb = (np.asarray(x.luminance_variance, dtype=np.float64) for x in (image, reference))
    if a.shape != b.shape or a.ndim != 2:
        raise ValueError(f"image shape {a.shape} differs from reference shape {b.shape}"
                         if a.shape != b.shape else f"luminances must be (H, W), got {a.shape}")
    if int(block) < 1:
        raise ValueError(f"block = {block}: must be >= 1")
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha = {alpha}: must lie in (0, 1)")
    for name, arr in (("image", a), ("reference", b)):
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} luminance has NaN or infinite values")
    for name, arr in (("image", va), ("reference", vb)):
        if not np.all(arr >= 0):
            raise ValueError(f"{name} luminance_variance must be >= 0 (spp >= 2: the "
                             "variance of a one-sample pixel is unknown)")
    scale = np.maximum(np.abs(b), 1e-6)
    noisy = (np.sqrt(va) > noise_free * scale) | (np.sqrt(vb) > noise_free * scale)
    if not noisy.any():
        raise ValueError("no pixel of either render has noise: nothing to z-test")
    if not np.all(np.isfinite(va[noisy])) or not np.all(np.isfinite(vb[noisy])):
        raise ValueError("luminance_variance is infinite (spp = 1 gives no variance; "
                         "render with spp >= 2)")
    diff = np.where(noisy, a - b, 0.0)
    var = np.where(noisy, va + vb, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(var > 0, diff / np.sqrt(var), 0.0)
    mean_z = float(diff.sum() / np.sqrt(var.sum()))
    block_diff, block_var = _block_sums(diff, int(block)), _block_sums(var, int(block))
    with np.errstate(divide="ignore", invalid="ignore"):
        block_z = np.where(block_var > 0, block_diff / np.sqrt(block_var), np.nan)
    tests = 1 + int(np.count_nonzero(np.isfinite(block_z)))
    per_test = 1.0 - (1.0 - alpha) ** (1.0 / tests)
    threshold = float(-ndtri(per_test / 2))
    worst = float(np.nanmax(np.abs(block_z)))
    ref_mean = float(b.mean())
    relative = float(a.mean() / ref_mean - 1.0) if ref_mean != 0 else float("nan")
    relative_se = float(np.sqrt(var.sum()) / b.size / abs(ref_mean)) if ref_mean else float("nan")
    quiet = int(np.count_nonzero(~noisy))
    messages = [
        f"whole image: z = {mean_z:.3g} (means {a.mean():.6g} and {ref_mean:.6g}, "
        f"relative difference {relative:+.3%} ± {relative_se:.3%})",
        f"blocks of {block}x{block}: largest |z| = {worst:.3g} of {tests - 1}; "
        f"threshold {threshold:.3g} (alpha {alpha:g} over {tests} z-tests)",
        f"{quiet} noise-free pixels compared with rtol {rtol:g}",
    ]
    failures = []
    if abs(mean_z) > threshold:
        failures.append(f"the whole-image means differ by {mean_z:.3g} standard errors")
    if worst > threshold:
        i, j = np.unravel_index(np.nanargmax(np.abs(block_z)), block_z.shape)
        failures.append(f"block ({i}, {j}) (rows {i * block}.., columns {j * block}..) "
                        f"differs by {block_z[i, j]:.3g} standard errors")
    if not np.allclose(a[~noisy], b[~noisy], rtol=rtol, atol=1e-6):
        failures.append(f"noise-free pixels differ by more than rtol {rtol:g}")
    messages.extend(f"FAILED: {f}" for f in failures)
    return RenderZTestResult(not failures, mean_z, block_z, threshold, z, relative, relative_se,
                             messages)
