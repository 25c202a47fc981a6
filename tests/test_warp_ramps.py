"""The tent, nonuniform tent, linear and square-concentric warps of
``mi.warp``: against Mitsuba 3 on the same numbers (float32 precision),
against their own densities (chi-square), round trips, and bad parameters."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats, warp


def _nonuniform_tent_pdf(a, b, c):
    def pdf(x):
        x = np.asarray(x, dtype=np.float64)
        rising = np.where(b > a, 2 * (x - a) / ((c - a) * max(b - a, 1e-300)), 0.0)
        falling = np.where(c > b, 2 * (c - x) / ((c - a) * max(c - b, 1e-300)), 0.0)
        return np.where((x >= a) & (x <= c), np.where(x <= b, rising, falling), 0.0)
    return pdf


def _linear_pdf(v0, v1):
    return lambda x: np.where((x >= 0) & (x <= 1), 2 * ((1 - x) * v0 + x * v1) / (v0 + v1), 0.0)


CHI2 = [
    ("interval_to_tent", lambda u: warp.interval_to_tent(u[:, 0]),
     lambda x: np.maximum(1 - np.abs(x), 0), (-1.0, 1.0)),
    ("square_to_tent", warp.square_to_tent, warp.square_to_tent_pdf, "plane"),
    ("nonuniform_tent(-1, 0, 2)", lambda u: warp.interval_to_nonuniform_tent(-1, 0, 2, u[:, 0]),
     _nonuniform_tent_pdf(-1, 0, 2), (-1.0, 2.0)),
    ("nonuniform_tent(0, 0.8, 1)", lambda u: warp.interval_to_nonuniform_tent(0, 0.8, 1, u[:, 0]),
     _nonuniform_tent_pdf(0, 0.8, 1), (0.0, 1.0)),
    ("nonuniform_tent(0, 1, 1)", lambda u: warp.interval_to_nonuniform_tent(0, 1, 1, u[:, 0]),
     _nonuniform_tent_pdf(0, 1, 1), (0.0, 1.0)),
    ("linear(1, 3)", lambda u: warp.interval_to_linear(1, 3, u[:, 0]), _linear_pdf(1, 3),
     "interval"),
    ("linear(2, 0)", lambda u: warp.interval_to_linear(2, 0, u[:, 0]), _linear_pdf(2, 0),
     "interval"),
    ("square_concentric", warp.square_to_uniform_square_concentric,
     lambda p: np.ones(len(p)), "square"),
]


@pytest.mark.parametrize("name,sample,pdf,domain", CHI2, ids=[c[0] for c in CHI2])
def test_chi2_against_own_density(name, sample, pdf, domain):
    result = stats.chi2_test(sample, pdf, domain, n=1_000_000, seed=7, test_count=len(CHI2))
    assert result.passed, result.message


def test_a_wrong_peak_is_rejected():
    result = stats.chi2_test(lambda u: warp.interval_to_nonuniform_tent(0, 0.3, 1, u[:, 0]),
                             _nonuniform_tent_pdf(0, 0.33, 1), (0.0, 1.0), n=1_000_000, seed=7)
    assert not result.passed


def test_round_trips_and_edges():
    u = mcs.uniform(10_000, 2, seed=1)
    assert np.allclose(warp.tent_to_interval(warp.interval_to_tent(u[:, 0])), u[:, 0], atol=1e-12, rtol=0)
    assert np.allclose(warp.tent_to_square(warp.square_to_tent(u)), u, atol=1e-12, rtol=0)
    for v0, v1 in [(1, 3), (2, 0), (0, 1), (1, 1.00001)]:
        x = warp.interval_to_linear(v0, v1, u[:, 0])
        assert np.allclose(warp.linear_to_interval(v0, v1, x), u[:, 0], atol=1e-12, rtol=0)
    assert warp.interval_to_tent(0.0) == -1 and warp.interval_to_tent(1.0) == 1
    # The peak at the right end: u = 1 gives the peak, not Mitsuba's 0/0.
    assert warp.interval_to_nonuniform_tent(0, 1, 1, 1.0) == 1.0
    assert np.array_equal(warp.square_to_uniform_square_concentric([0.5, 0.5]), [0.0, 0.0])
    assert warp.square_to_tent_pdf([1.0, 0.0]) == 0 and warp.square_to_tent_pdf([0.0, 0.0]) == 1
    assert warp.square_to_tent_pdf([1.5, 0.0]) == 0


def test_bad_parameters_name_themselves():
    with pytest.raises(ValueError, match="b = 3"):
        warp.interval_to_nonuniform_tent(0, 3, 2, 0.5)
    with pytest.raises(ValueError, match="c = 0"):
        warp.interval_to_nonuniform_tent(0, 0, 0, 0.5)
    with pytest.raises(ValueError, match="a = NaN"):
        warp.interval_to_nonuniform_tent(float("nan"), 0, 1, 0.5)
    with pytest.raises(ValueError, match="v0 = -1"):
        warp.interval_to_linear(-1, 1, 0.5)
    with pytest.raises(ValueError, match="not both be 0"):
        warp.linear_to_interval(0, 0, 0.5)
    with pytest.raises(ValueError, match="sample"):
        warp.interval_to_tent(1.5)
    # Huge but valid parameters: the same distribution as their ratio.
    assert np.array_equal(warp.interval_to_linear(1e200, 3e200, [0.3, 0.9]),
                          warp.interval_to_linear(1, 3, [0.3, 0.9]))
    x = warp.interval_to_linear(1e30, 0, np.linspace(0, 1, 11, dtype=np.float32))
    assert np.isfinite(x).all() and (x >= 0).all() and (x <= 1).all()
    with pytest.raises(ValueError, match="c - a must be a finite"):
        warp.interval_to_nonuniform_tent(-1e308, 0, 1e308, 0.5)


def _mi_1d(mi, fn, x, *args):
    """A mi.warp function of one Float per point, on x (n,) → numpy (n,)."""
    if mi.variant().startswith("scalar"):
        return np.array([float(fn(*args, float(v))) for v in x])
    return np.array(fn(*args, mi.Float(x.astype(np.float32))), dtype=np.float64)


def _mi_2d(mi, fn, x):
    """A mi.warp function of one Point2f per point, on x (n, 2) → (n, k)."""
    if mi.variant().startswith("scalar"):
        return np.array([np.array(fn(mi.Point2f(*row)), dtype=np.float64).reshape(-1)
                         for row in x])
    out = np.array(fn(mi.Point2f(x[:, 0].astype(np.float32), x[:, 1].astype(np.float32))),
                   dtype=np.float64)
    return out.T if out.ndim == 2 else out


@pytest.mark.mitsuba
def test_agree_with_mitsuba(mi):
    n = 64 if mi.variant().startswith("scalar") else 20_000
    u = mcs.uniform(n, 2, seed=3, dtype=np.float32).astype(np.float64)
    u = np.clip(u, 1e-3, 1 - 1e-3)
    close = dict(rtol=2e-5, atol=2e-6)
    t = warp.interval_to_tent(u[:, 0])
    assert np.allclose(t, _mi_1d(mi, mi.warp.interval_to_tent, u[:, 0]), **close)
    assert np.allclose(warp.tent_to_interval(t), _mi_1d(mi, mi.warp.tent_to_interval, t), **close)
    p = warp.square_to_tent(u)
    assert np.allclose(p, _mi_2d(mi, mi.warp.square_to_tent, u), **close)
    assert np.allclose(warp.tent_to_square(p), _mi_2d(mi, mi.warp.tent_to_square, p), **close)
    assert np.allclose(warp.square_to_tent_pdf(p),
                       _mi_2d(mi, mi.warp.square_to_tent_pdf, p).reshape(-1), **close)
    for a, b, c in [(-1, 0, 2), (0, 0.3, 1), (0, 0, 1)]:
        ours = warp.interval_to_nonuniform_tent(a, b, c, u[:, 0])
        theirs = _mi_1d(mi, mi.warp.interval_to_nonuniform_tent, u[:, 0], a, b, c)
        assert np.allclose(ours, theirs, rtol=1e-4, atol=1e-5), (a, b, c)
    for v0, v1 in [(1, 3), (1, 0), (0, 1), (2, 2.00001)]:
        x = warp.interval_to_linear(v0, v1, u[:, 0])
        assert np.allclose(x, _mi_1d(mi, mi.warp.interval_to_linear, u[:, 0], v0, v1), **close)
        assert np.allclose(warp.linear_to_interval(v0, v1, x),
                           _mi_1d(mi, mi.warp.linear_to_interval, x, v0, v1), **close)
    away = u[np.abs(u - 0.5).max(axis=1) > 1e-3]
    assert np.allclose(warp.square_to_uniform_square_concentric(away),
                       _mi_2d(mi, mi.warp.square_to_uniform_square_concentric, away), **close)
