"""Every warp against its own density (chi-square, 10^6 samples), including
the cosine-power lobe from n = 0 to n = 1000, and a rejection of a wrong
exponent (a test that can fail)."""

import numpy as np
import pytest

from mcsample import stats, warp

CASES = [
    ("uniform_disk", warp.square_to_uniform_disk, warp.square_to_uniform_disk_pdf, "disk", 4),
    ("uniform_disk_concentric", warp.square_to_uniform_disk_concentric,
     warp.square_to_uniform_disk_concentric_pdf, "disk", 4),
    ("uniform_sphere", warp.square_to_uniform_sphere, warp.square_to_uniform_sphere_pdf,
     "sphere", 4),
    ("uniform_hemisphere", warp.square_to_uniform_hemisphere,
     warp.square_to_uniform_hemisphere_pdf, "hemisphere", 4),
    ("cosine_hemisphere", warp.square_to_cosine_hemisphere,
     warp.square_to_cosine_hemisphere_pdf, "sphere", 4),
    ("cosine_hemisphere_polar", lambda u: warp.square_to_cosine_hemisphere(u, method="polar"),
     warp.square_to_cosine_hemisphere_pdf, "hemisphere", 4),
    ("uniform_cone_0.3", lambda u: warp.square_to_uniform_cone(u, 0.3),
     lambda d: warp.square_to_uniform_cone_pdf(d, 0.3), "sphere", 16),
    ("uniform_cone_-0.7", lambda u: warp.square_to_uniform_cone(u, -0.7),
     lambda d: warp.square_to_uniform_cone_pdf(d, -0.7), "sphere", 16),
    ("uniform_triangle", warp.square_to_uniform_triangle, warp.square_to_uniform_triangle_pdf,
     "square", 24),
    ("interval_to_power_0", lambda u: warp.interval_to_power(u[:, 0], 0.0),
     lambda x: warp.interval_to_power_pdf(x, 0.0), "interval", 4),
    ("interval_to_power_7.5", lambda u: warp.interval_to_power(u[:, 0], 7.5),
     lambda x: warp.interval_to_power_pdf(x, 7.5), "interval", 4),
]

# Cosine-power lobes: the hemisphere domain zoomed toward the pole so that
# sharp lobes spread over many rows; finer integration for the sharp ones.
LOBES = [(0.0, 1.0, 4), (1.0, 1.0, 4), (10.0, 2.0, 8), (100.0, 3.0, 16), (1000.0, 4.0, 16)]

TEST_COUNT = len(CASES) + len(LOBES)


@pytest.mark.parametrize("name,sample,pdf,domain,ires", CASES, ids=[c[0] for c in CASES])
def test_chi2_every_warp(name, sample, pdf, domain, ires):
    result = stats.chi2_test(sample, pdf, domain, n=1_000_000, ires=ires, seed=5,
                             test_count=TEST_COUNT)
    assert result.passed, result.message


@pytest.mark.parametrize("exponent,zoom,ires", LOBES, ids=[f"n={e:g}" for e, _, _ in LOBES])
def test_chi2_cosine_power_lobes(exponent, zoom, ires):
    result = stats.chi2_test(
        lambda u: warp.square_to_cosine_power_hemisphere(u, exponent),
        lambda d: warp.square_to_cosine_power_hemisphere_pdf(d, exponent),
        stats.HemisphereDomain(zoom), n=1_000_000, ires=ires, seed=6, test_count=TEST_COUNT)
    assert result.passed, result.message
    # The lobe is resolved: many cells hold samples, not a handful at the pole.
    assert np.count_nonzero(result.histogram.sum(axis=1) > 100) >= 20


@pytest.mark.parametrize("exponent,zoom,ires", LOBES[2:], ids=[f"n={e:g}" for e, _, _ in LOBES[2:]])
def test_chi2_rejects_the_next_exponent(exponent, zoom, ires):
    result = stats.chi2_test(
        lambda u: warp.square_to_cosine_power_hemisphere(u, exponent),
        lambda d: warp.square_to_cosine_power_hemisphere_pdf(d, exponent + 1 + exponent / 20),
        stats.HemisphereDomain(zoom), n=1_000_000, ires=ires, seed=6)
    assert not result.passed


def test_zoomed_domain_integrates_the_hemisphere():
    dom = stats.HemisphereDomain(3.0)
    xy = np.stack([np.zeros(1001), np.linspace(0, 1, 1001)], axis=1)
    z = dom.from_param(xy)[:, 2]
    assert np.allclose(dom.to_param(dom.from_param(xy))[:, 1], xy[:, 1])
    # ∫ jacobian dy over [0, 1] = ∫ d(cos θ) over [0, 1] = 1.
    assert abs(np.trapezoid(dom.jacobian(xy), xy[:, 1]) - 1) < 1e-4
    assert z[0] == 0 and z[-1] == 1
