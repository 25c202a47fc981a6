"""``out=`` of the distributions' batch methods (and of the bilinear
warps, which return two arrays): the result is written into the caller's
arrays, bit for bit what the plain call returns, and a bad ``out`` is a
clear exception."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import warp

N = 1000
W1 = np.random.default_rng(3).gamma(0.7, size=60)
W2 = np.random.default_rng(4).gamma(0.7, size=(12, 30))


def _u(k, dtype=np.float64):
    u = mcs.uniform(N, k, seed=11).astype(dtype)
    return u[:, 0] if k == 1 else u


def _like(result):
    """Arrays of the shapes and dtypes of ``result`` (a tuple for a result
    of several arrays), filled with -7, which no result holds: a call that
    wrote nothing into them cannot pass for one that did."""
    if isinstance(result, np.ndarray):
        return np.full_like(result, -7)
    return tuple(np.full_like(a, -7) for a in result)


def _cases(dtype):
    """(name, call taking out=) for every batch method with one or two results."""
    d1, a1, d2 = mcs.Discrete1D(W1), mcs.AliasTable(W1), mcs.Discrete2D(W2)
    p1 = mcs.PiecewiseConstant1D(W1, a=-1.0, b=2.0)
    p2 = mcs.PiecewiseConstant2D(W2, domain=((0.0, 3.0), (-1.0, 1.0)))
    u1, u2 = _u(1, dtype), _u(2, dtype)
    x1 = p1.sample(u1).x
    x2 = p2.sample(u2).x
    idx2 = d2.sample(u2)
    return [
        ("Discrete1D.sample", lambda **o: d1.sample(u1, **o)),
        ("Discrete1D.sample_reuse", lambda **o: tuple(d1.sample_reuse(u1, **o))),
        ("Discrete1D.pmf(i)", lambda **o: d1.pmf(d1.sample(u1), **o)),
        ("Discrete1D.pmf()", lambda **o: d1.pmf(**o)),
        ("AliasTable.sample", lambda **o: a1.sample(u1, **o)),
        ("AliasTable.pmf(i)", lambda **o: a1.pmf(a1.sample(u1), **o)),
        ("Discrete2D.sample", lambda **o: d2.sample(u2, **o)),
        ("Discrete2D.sample_reuse", lambda **o: tuple(d2.sample_reuse(u2, **o))),
        ("Discrete2D.pmf(idx)", lambda **o: d2.pmf(idx2, **o)),
        ("Discrete2D.pmf()", lambda **o: d2.pmf(**o)),
        ("PiecewiseConstant1D.sample", lambda **o: tuple(p1.sample(u1, **o))),
        ("PiecewiseConstant1D.pdf", lambda **o: p1.pdf(x1, **o)),
        ("PiecewiseConstant1D.cdf", lambda **o: p1.cdf(x1, **o)),
        ("PiecewiseConstant1D.invert", lambda **o: p1.invert(x1, **o)),
        ("PiecewiseConstant2D.sample", lambda **o: tuple(p2.sample(u2, **o))),
        ("PiecewiseConstant2D.pdf", lambda **o: p2.pdf(x2, **o)),
        ("PiecewiseConstant2D.invert", lambda **o: p2.invert(x2, **o)),
        ("square_to_bilinear", lambda **o: warp.square_to_bilinear(1.0, 2.0, 0.5, 3.0, u2, **o)),
        ("bilinear_to_square", lambda **o: warp.bilinear_to_square(1.0, 2.0, 0.5, 3.0, u2, **o)),
    ]


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_out_receives_the_plain_calls_bits(dtype):
    for name, call in _cases(dtype):
        plain = call()
        out = _like(plain)
        got = call(out=out)
        if isinstance(out, tuple):
            assert all(g is o for g, o in zip(got, out)), name
            for g, p in zip(got, plain):
                assert g.dtype == p.dtype and np.array_equal(g, p), name
        else:
            assert got is out, name
            assert got.dtype == plain.dtype and np.array_equal(got, plain), name
        # out=None is the plain call.
        again = call(out=None)
        pairs = zip(again, plain) if isinstance(plain, tuple) else [(again, plain)]
        assert all(np.array_equal(a, p) for a, p in pairs), name


def test_bad_out_is_refused():
    d1, d2 = mcs.Discrete1D(W1), mcs.Discrete2D(W2)
    p1 = mcs.PiecewiseConstant1D(W1)
    u1, u2 = _u(1), _u(2)
    with pytest.raises(TypeError, match="dtype int64"):
        d1.sample(u1, out=np.empty(N))
    with pytest.raises(ValueError, match=r"out must have shape \(1000, 2\)"):
        d2.sample(u2, out=np.empty((N, 3), np.int64))
    with pytest.raises(ValueError, match=r"out must have shape \(12, 30\)"):
        d2.pmf(out=np.empty(360))
    with pytest.raises(TypeError, match=r"out must be a tuple of two arrays: \(x, pdf\)"):
        p1.sample(u1, out=np.empty(N))
    with pytest.raises(TypeError, match=r"out must be a tuple of two arrays: \(index, u\)"):
        d1.sample_reuse(u1, out=(np.empty(N, np.int64),))
    with pytest.raises(TypeError, match=r"out\[1\] must have dtype float64"):
        p1.sample(u1, out=(np.empty(N), np.empty(N, np.float32)))
    shared = np.empty(N)
    with pytest.raises(ValueError, match="share memory"):
        p1.sample(u1, out=(shared, shared))
    with pytest.raises(ValueError, match="share memory"):
        p1.pdf(u1, out=u1)
    # The inputs are still checked when writing into out.
    with pytest.raises(ValueError, match=r"u\[0\] = 1\.5"):
        d1.sample(np.full(N, 1.5), out=np.empty(N, np.int64))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_batches_equal_single_draws(dtype):
    # The batch methods draw in groups (the tables' prefetching samplers):
    # each point gets what a call with that point alone returns.
    d1, d2 = mcs.Discrete1D(W1), mcs.Discrete2D(W2)
    p1 = mcs.PiecewiseConstant1D(W1, a=-1.0, b=2.0)
    p2 = mcs.PiecewiseConstant2D(W2, domain=((0.0, 3.0), (-1.0, 1.0)))
    u1 = np.concatenate([_u(1, dtype)[:197], np.array([0.0, 1.0], dtype)])
    u2 = np.concatenate([_u(2, dtype)[:197], np.array([[0.0, 1.0], [1.0, 0.0]], dtype)])
    for call, u in [(d1.sample_reuse, u1), (d2.sample_reuse, u2), (d2.sample, u2),
                    (p1.sample, u1), (p2.sample, u2)]:
        batch = call(u)
        parts = batch if isinstance(batch, np.ndarray) else tuple(batch)
        for k in range(len(u)):
            one = call(u[k])
            ones = one if isinstance(one, np.ndarray) else tuple(one)
            if isinstance(parts, tuple):
                for whole, single in zip(parts, ones):
                    assert np.array_equal(whole[k], single), (call, k)
            else:
                assert np.array_equal(parts[k], ones), (call, k)


def test_float32_reused_numbers_stay_below_one():
    # A rescaled u of 1 - 2^-53 rounds to 1.0 in float32: clamped in float32.
    d = mcs.Discrete1D([1.0, 3.0])
    u = np.array([0.25, 1.0, np.nextafter(np.float32(0.25), np.float32(0))], np.float32)
    _, r = d.sample_reuse(u)
    assert r.dtype == np.float32 and np.all(r < 1.0) and np.all(r >= 0.0)
