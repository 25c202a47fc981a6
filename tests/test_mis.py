"""MIS heuristics: definitions, degenerate cases (never NaN), broadcasting,
and the weights of two strategies summing to one."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import mis


def test_values_and_degenerate_cases():
    a = np.array([1.0, 0.0, 0.0, 2.0, np.inf, 2.0, np.inf, 1e300, 1e-300])
    b = np.array([3.0, 0.0, 2.0, 0.0, 2.0, np.inf, np.inf, 1e300, 1e-300])
    bal = mis.balance_heuristic(a, b)
    assert np.allclose(bal, [0.25, 0, 0, 1, 1, 0, 0.5, 0.5, 0.5])
    pw = mis.power_heuristic(a, b)
    assert np.allclose(pw, [0.1, 0, 0, 1, 1, 0, 0.5, 0.5, 0.5])
    assert not np.any(np.isnan(bal)) and not np.any(np.isnan(pw))
    assert mis.power_heuristic(1.0, 2.0, beta=3.0) == pytest.approx(1 / 9)


def test_pair_sums_to_one_and_broadcasts():
    rng = np.random.default_rng(0)
    a, b = rng.random(1000) * 5, rng.random(1000) * 5
    for h in (mis.balance_heuristic, mis.power_heuristic):
        assert np.allclose(h(a, b) + h(b, a), 1.0)
    assert mis.balance_heuristic(a, 2.0).shape == (1000,)
    assert np.ndim(mis.balance_heuristic(1.0, 2.0)) == 0
    assert mis.balance_heuristic(a.astype(np.float32), b).dtype == np.float32


@pytest.mark.parametrize("call,fragment", [
    (lambda: mis.balance_heuristic([1.0, -1.0], [1.0, 1.0]), "pdf_a[1] = -1"),
    (lambda: mis.balance_heuristic([1.0], [np.nan]), "pdf_b[0] = NaN"),
    (lambda: mis.power_heuristic([1.0, 2.0], [1.0, 2.0, 3.0]), "pdf_b"),
    (lambda: mis.power_heuristic(1.0, 1.0, beta=0.0), "beta = 0"),
])
def test_bad_input(call, fragment):
    with pytest.raises(ValueError) as info:
        call()
    assert fragment in str(info.value)


def test_mis_estimator_is_unbiased_for_a_known_integral():
    # ∫ over the hemisphere of cos^5 θ dω = 2π/6: combine cosine-hemisphere
    # and cosine-power (n = 5) sampling with the power heuristic.
    from mcsample import warp
    n = 200_000
    u = mcs.uniform(n, 4, seed=3)
    f = lambda d: np.maximum(d[:, 2], 0) ** 5  # noqa: E731
    da = warp.square_to_cosine_hemisphere(u[:, :2])
    db = warp.square_to_cosine_power_hemisphere(u[:, 2:], 5.0)
    pa = lambda d: warp.square_to_cosine_hemisphere_pdf(d)  # noqa: E731
    pb = lambda d: warp.square_to_cosine_power_hemisphere_pdf(d, 5.0)  # noqa: E731
    est = (mis.power_heuristic(pa(da), pb(da)) * f(da) / pa(da)
           + mis.power_heuristic(pb(db), pa(db)) * f(db) / pb(db))
    assert abs(est.mean() - 2 * np.pi / 6) < 4 * est.std() / np.sqrt(n)
