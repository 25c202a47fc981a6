"""Distributions: each sampler against its own pmf / pdf (chi-square),
agreement with numpy, inverse∘sample = identity, normalisation, u = 1, and
rejection sampling's acceptance rate."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats

# Accepting chi-square tests in this file (Šidák correction).
TEST_COUNT = 8

# A grid over [0, 1] with both ends and points within 1e-12 of them.
EDGE_GRID = np.unique(np.concatenate([np.linspace(0, 1, 2001), [1e-12, 1 - 1e-12, 0.0, 1.0]]))


@pytest.fixture(scope="module")
def weights():
    w = np.random.default_rng(3).gamma(0.7, size=60)
    w[[0, 1, 17, 30, 58, 59]] = 0.0  # leading, interior and trailing zeros
    return w


def _cells_pdf(table_pmf, shape=None):
    """Density of a point (index + offset) spread uniformly over its cell."""
    def pdf(x):
        x = np.asarray(x)
        if x.ndim == 1:
            i = np.clip(np.floor(x).astype(int), 0, len(table_pmf) - 1)
            return table_pmf[i]
        r = np.clip(np.floor(x[:, 1]).astype(int), 0, shape[0] - 1)
        c = np.clip(np.floor(x[:, 0]).astype(int), 0, shape[1] - 1)
        return table_pmf[r, c]
    return pdf


def test_discrete1d_pmf_cdf_sum_equal_numpy(weights):
    d = mcs.Discrete1D(weights)
    assert len(d) == 60
    assert np.array_equal(d.pmf(), weights / weights.sum())
    assert np.allclose(d.pmf(np.arange(60)), weights / weights.sum(), rtol=0, atol=1e-17)
    assert np.allclose(d.cdf, np.cumsum(weights) / weights.sum(), rtol=1e-15)
    assert d.cdf[-1] == 1.0 and np.all(np.diff(d.cdf) >= 0)
    assert d.sum == pytest.approx(weights.sum(), rel=1e-15)
    assert np.ndim(d.pmf(3)) == 0


def test_alias_pmf_equals_numpy(weights):
    a = mcs.AliasTable(weights)
    assert np.allclose(a.pmf(), weights / weights.sum(), rtol=1e-15, atol=0)
    assert np.array_equal(a.pmf(), mcs.Discrete1D(weights).pmf())


@pytest.mark.parametrize("table", ["discrete", "alias"])
def test_zero_weights_never_sampled(weights, table):
    d = mcs.Discrete1D(weights) if table == "discrete" else mcs.AliasTable(weights)
    idx = d.sample(np.concatenate([EDGE_GRID, mcs.uniform(200_000, 1, seed=1)[:, 0]]))
    assert idx.dtype == np.int64
    assert np.all(weights[idx] > 0)


def test_discrete1d_chi2_with_reuse(weights):
    d = mcs.Discrete1D(weights)

    def sample(u):
        i, r = d.sample_reuse(u[:, 0])
        return i + r
    result = stats.chi2_test(sample, _cells_pdf(d.pmf()), (0, 60), sample_dim=1, res=60,
                             seed=2, test_count=TEST_COUNT)
    assert result.passed, result.message


def test_alias_chi2(weights):
    a = mcs.AliasTable(weights)
    result = stats.chi2_test(lambda u: a.sample(u[:, 0]) + 0.5, _cells_pdf(a.pmf()), (0, 60),
                             sample_dim=1, res=60, seed=2, test_count=TEST_COUNT)
    assert result.passed, result.message


@pytest.mark.parametrize("table", ["discrete", "alias"])
def test_two_sample_against_numpy_choice(weights, table):
    d = mcs.Discrete1D(weights) if table == "discrete" else mcs.AliasTable(weights)
    ours = d.sample(mcs.uniform(400_000, 1, seed=9)[:, 0]) + 0.5
    theirs = np.random.default_rng(9).choice(60, size=400_000, p=weights / weights.sum()) + 0.5
    result = stats.two_sample_test(ours, theirs, (0, 60), res=60)
    assert result.passed, result.message
    # ...and the test sees a wrong table.
    skewed = weights * (1 + 0.3 * (np.arange(60) > 30))
    wrong = np.random.default_rng(9).choice(60, size=400_000, p=skewed / skewed.sum()) + 0.5
    assert not stats.two_sample_test(ours, wrong, (0, 60), res=60).passed


def test_sample_reuse_is_a_fresh_uniform(weights):
    d = mcs.Discrete1D(weights)
    i, r = d.sample_reuse(EDGE_GRID)
    assert np.all((r >= 0) & (r < 1))
    u = mcs.uniform(500_000, 1, seed=4)[:, 0]
    i, r = d.sample_reuse(u)
    # Within the most likely entry the rescaled numbers are uniform.
    sel = r[i == np.argmax(weights)]
    counts = np.histogram(sel, bins=10, range=(0, 1))[0]
    assert stats.two_sample_test(sel, np.random.default_rng(1).random(len(sel)), (0, 1), res=10).passed
    assert counts.min() > 0.8 * len(sel) / 10


def blocked_cumsum(w, block=8000):
    """Running sums as Discrete1D accumulates them: in order within blocks
    of 8000 entries, each block then offset by the sum of those before it."""
    parts = [np.cumsum(w[s:s + block]) for s in range(0, len(w), block)]
    offsets = np.cumsum([0.0] + [p[-1] for p in parts[:-1]])
    return np.concatenate([p + o for p, o in zip(parts, offsets)])


def test_large_table_guide_matches_binary_search(rng):
    w = rng.random(100_000) ** 4
    w[rng.random(100_000) < 0.2] = 0
    d = mcs.Discrete1D(w)
    cdf = blocked_cumsum(w)  # 13 blocks, summed as the table sums them
    u = np.concatenate([rng.random(200_000), np.minimum(cdf / cdf[-1], 1), [0.0, 1.0]])
    # numpy's searchsorted 'left' gives the first i with C[i] >= u * sum.
    ref = np.searchsorted(cdf, u * cdf[-1], side="left")
    ref = np.clip(ref, np.flatnonzero(w)[0], np.flatnonzero(w)[-1])
    got = d.sample(u)
    assert np.array_equal(got, ref)
    assert np.all(w[got] > 0)


def test_discrete2d_pmf_and_chi2(rng):
    w = rng.random((7, 13)) ** 3
    w[2] = 0.0  # a zero row
    w[:, 5] = 0.0  # a zero column
    d = mcs.Discrete2D(w)
    assert d.shape == (7, 13)
    assert np.allclose(d.pmf(), w / w.sum(), rtol=1e-15)
    idx = np.array([[0, 0], [6, 12], [3, 4]])
    assert np.allclose(d.pmf(idx), w[idx[:, 0], idx[:, 1]] / w.sum())

    def sample(u):
        cells, r = d.sample_reuse(u)
        return cells[:, ::-1] + r  # (col + r0, row + r1): x along columns
    result = stats.chi2_test(sample, _cells_pdf(d.pmf(), (7, 13)), ((0, 13), (0, 7)),
                             res=(7, 13), seed=3, test_count=TEST_COUNT)
    assert result.passed, result.message
    cells = d.sample(np.concatenate([np.stack([EDGE_GRID, EDGE_GRID[::-1]], 1),
                                     mcs.uniform(100_000, 2, seed=8)]))
    assert np.all(w[cells[:, 0], cells[:, 1]] > 0)


def test_piecewise1d_chi2_inverse_and_normalisation(rng):
    values = rng.random(40) ** 2
    values[[0, 10, 11, 39]] = 0
    p = mcs.PiecewiseConstant1D(values, a=-2.0, b=3.0)
    assert p.integral == pytest.approx(values.sum() * 5 / 40)
    result = stats.chi2_test(lambda u: p.sample(u[:, 0])[0], p.pdf, (-2.0, 3.0), sample_dim=1,
                             res=200, seed=4, test_count=TEST_COUNT)
    assert result.passed, result.message
    x, pdf = p.sample(EDGE_GRID)
    assert np.all((x >= -2) & (x <= 3)) and np.all(pdf > 0)
    assert np.array_equal(pdf, p.pdf(x))
    assert np.abs(p.invert(x) - EDGE_GRID).max() < 1e-9
    assert np.allclose(p.cdf(x), p.invert(x))
    # ∫ pdf = 1 (midpoint rule on a grid aligned with the cells).
    grid = -2 + (np.arange(40 * 50) + 0.5) * (5 / (40 * 50))
    assert abs(p.pdf(grid).sum() * 5 / len(grid) - 1) < 1e-12
    assert p.pdf([-2.5, 3.5]).tolist() == [0, 0]
    assert p.cdf([-5.0, 5.0]).tolist() == [0, 1]


def test_piecewise1d_float32(rng):
    p = mcs.PiecewiseConstant1D(rng.random(16) + 0.1, a=0.0, b=0.1)
    x, pdf = p.sample(EDGE_GRID.astype(np.float32))
    assert x.dtype == np.float32 and pdf.dtype == np.float32
    assert np.all((x >= 0) & (x <= np.float32(0.1)))
    assert np.array_equal(pdf, p.pdf(x))


def test_piecewise2d_spiky_chi2_inverse_and_normalisation():
    rng = np.random.default_rng(21)
    values = rng.random((24, 48)) * 0.01
    values[rng.integers(0, 24, 30), rng.integers(0, 48, 30)] = rng.random(30) * 500
    values[5] = 0
    values[:, 7] = 0
    dom = ((-1.0, 3.0), (0.5, 2.5))
    p = mcs.PiecewiseConstant2D(values, domain=dom)
    assert p.shape == (24, 48) and p.domain == dom
    result = stats.chi2_test(lambda u: p.sample(u)[0], p.pdf, dom, res=(48, 96), seed=5,
                             test_count=TEST_COUNT)
    assert result.passed, result.message
    u = np.stack(np.meshgrid(EDGE_GRID[::20], EDGE_GRID[::20]), -1).reshape(-1, 2)
    u = np.concatenate([u, [[0, 0], [1, 1], [1, 0], [0, 1], [1e-12, 1 - 1e-12]]])
    xy, pdf = p.sample(u)
    assert np.all(pdf > 0) and np.array_equal(pdf, p.pdf(xy))
    assert np.all((xy[:, 0] >= -1) & (xy[:, 0] <= 3) & (xy[:, 1] >= 0.5) & (xy[:, 1] <= 2.5))
    assert np.abs(p.invert(xy) - u).max() < 1e-9
    gx = -1 + (np.arange(48 * 8) + 0.5) * (4 / (48 * 8))
    gy = 0.5 + (np.arange(24 * 8) + 0.5) * (2 / (24 * 8))
    grid = np.stack(np.meshgrid(gx, gy), -1).reshape(-1, 2)
    assert abs(p.pdf(grid).sum() * 8 / len(grid) - 1) < 1e-9


def _two_bumps(p):
    x, y = p[:, 0], p[:, 1]
    return np.exp(-((x - 0.3) ** 2 + (y - 0.6) ** 2) / 0.02) + 0.5 * (x > 0.7)


def test_rejection_sample_chi2_and_acceptance():
    # The normalised density on [0, 1]^2: integral of the bumps by quadrature.
    g = (np.arange(2000) + 0.5) / 2000
    grid = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    integral = _two_bumps(grid).mean()
    samples, acceptance = mcs.rejection_sample(_two_bumps, 1.5, ((0, 1), (0, 1)), 1_000_000,
                                               seed=3)
    assert samples.shape == (1_000_000, 2)
    expected = integral / 1.5
    # Binomial standard error of the rate over >= 10^6 proposals is < 5e-4.
    assert abs(acceptance - expected) < 2.5e-3, (acceptance, expected)
    result = stats.chi2_test(lambda u: samples, lambda p: _two_bumps(p) / integral, "square",
                             ires=8, seed=0, test_count=TEST_COUNT)
    assert result.passed, result.message


def test_rejection_sample_interval_and_determinism():
    pdf = lambda x: 3 * x ** 2  # noqa: E731
    a, acc = mcs.rejection_sample(pdf, 3.0, (0, 1), 20_000, seed=1)
    b, _ = mcs.rejection_sample(pdf, 3.0, (0, 1), 20_000, seed=1)
    assert a.shape == (20_000,) and np.array_equal(a, b)
    assert abs(acc - 1 / 3) < 0.02
    assert abs(a.mean() - 0.75) < 0.01
