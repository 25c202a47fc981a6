"""Distributions against Mitsuba 3's DiscreteDistribution and
DiscreteDistribution2D on the same u (skipped without Mitsuba)."""

import numpy as np
import pytest

import mcsample as mcs

pytestmark = pytest.mark.mitsuba


def _u(n, seed):
    # float32 numbers, so both libraries see the same u.
    return mcs.uniform(n, 2, seed=seed, dtype=np.float32).astype(np.float64)


def _weights():
    # Small integers: every running sum is exact in float32 and float64.
    w = np.random.default_rng(5).integers(0, 9, size=200).astype(np.float64)
    w[[0, 1, 100, 199]] = 0
    return w


def _mi_discrete(mi, w):
    return mi.DiscreteDistribution(w.astype(np.float32))


def _apply(mi, fn, u):
    if mi.variant().startswith("scalar"):
        return [fn(float(x)) for x in u]
    return fn(mi.Float(u.astype(np.float32)))


def test_discrete1d_sample_and_pmf_equal_mitsuba(mi):
    w = _weights()
    theirs = _mi_discrete(mi, w)
    n = 2000 if mi.variant().startswith("scalar") else 200_000
    u = np.concatenate([_u(n, 1)[:, 0], [0.0, 1.0]])
    ours = mcs.Discrete1D(w)
    if mi.variant().startswith("scalar"):
        their_idx = np.array([theirs.sample(float(x)) for x in u])
        reuse = [theirs.sample_reuse(float(x)) for x in u]
        their_ri = np.array([r[0] for r in reuse])
        their_r = np.array([r[1] for r in reuse])
        their_pmf = np.array([theirs.eval_pmf_normalized(int(i)) for i in range(len(w))])
    else:
        their_idx = np.array(theirs.sample(mi.Float(u.astype(np.float32))))
        ri, r = theirs.sample_reuse(mi.Float(u.astype(np.float32)))
        their_ri, their_r = np.array(ri), np.array(r)
        their_pmf = np.array(theirs.eval_pmf_normalized(mi.UInt32(np.arange(len(w)))))
    # u·sum is exact in float64 here, but Mitsuba rounds it to float32:
    # indices may differ only where u·sum lies within float32 round-off of a
    # running sum.
    idx = ours.sample(u)
    differ = idx != their_idx
    cdf = np.cumsum(w)
    near = np.min(np.abs(u[:, None] * w.sum() - cdf[None, :]), axis=1) < 1e-4 * w.sum()
    assert np.all(near[differ]), u[differ & ~near][:5]
    assert differ.mean() < 1e-3
    i, r = ours.sample_reuse(u)
    assert np.array_equal(i, idx)
    same = ~differ
    assert np.allclose(r[same], their_r[same], atol=2e-4)
    assert np.allclose(ours.pmf(), their_pmf, rtol=1e-6)


def test_discrete2d_same_cells_as_mitsuba(mi):
    w = np.random.default_rng(6).integers(0, 5, size=(9, 14)).astype(np.float64)
    w[3] = 0
    theirs = mi.DiscreteDistribution2D(w.astype(np.float32))
    ours = mcs.Discrete2D(w)
    n = 500 if mi.variant().startswith("scalar") else 50_000
    u = _u(n, 2)
    if mi.variant().startswith("scalar"):
        res = [theirs.sample(mi.Point2f(*row)) for row in u]
        their_cells = np.array([[int(r[0][1]), int(r[0][0])] for r in res])
        their_pdf = np.array([r[1] for r in res])
    else:
        pos, pdf, _ = theirs.sample(mi.Point2f(u[:, 0].astype(np.float32),
                                               u[:, 1].astype(np.float32)))
        p = np.array(pos)
        p = p.T if p.shape[0] == 2 and p.shape[1] != 2 else p
        their_cells = p[:, ::-1].astype(np.int64)  # Mitsuba's Point2u is (col, row)
        their_pdf = np.array(pdf)
    cells = ours.sample(u)
    same = np.all(cells == their_cells, axis=1)
    # Same assignment of u (row by u[1], column by u[0]); boundary round-off
    # in float32 may move a handful.
    assert same.mean() > 0.999, same.mean()
    assert np.allclose(ours.pmf(cells[same]), their_pdf[same], rtol=1e-5)
