"""The validation kit: chi2_test must accept right samplers and reject wrong
ones (each rejection is a test that could fail), and explain why."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats, warp

# Accepting tests in this file, for the Šidák correction.
ACCEPT_COUNT = 7


def cos2_pdf(d):
    """cos^2 lobe: 3/(2 pi) cos^2 theta on the upper hemisphere."""
    return warp.square_to_cosine_power_hemisphere_pdf(d, 2.0)


def disk_r_equals_u(u):
    """The classic mistake: r = u instead of sqrt(u) crowds the centre."""
    r, phi = u[:, 1], 2 * np.pi * u[:, 0]
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def triangle_pdf(p):
    return warp.square_to_uniform_triangle_pdf(p)


@pytest.mark.parametrize("sample,pdf,domain,ires", [
    (warp.square_to_uniform_sphere, warp.square_to_uniform_sphere_pdf, "sphere", 4),
    (warp.square_to_cosine_hemisphere, warp.square_to_cosine_hemisphere_pdf, "hemisphere", 4),
    (warp.square_to_cosine_hemisphere, warp.square_to_cosine_hemisphere_pdf, "sphere", 4),
    (warp.square_to_uniform_disk, warp.square_to_uniform_disk_pdf, "disk", 4),
    # The triangle's diagonal edge cuts through cells: the density jumps
    # inside them, which 4 trapezoid points per axis integrate too coarsely.
    (warp.square_to_uniform_triangle, triangle_pdf, "square", 24),
    (lambda u: u, lambda p: np.ones(len(p)), "square", 4),
    (lambda u: warp.interval_to_power(u[:, 0], 3.0),
     lambda x: warp.interval_to_power_pdf(x, 3.0), "interval", 4),
], ids=["sphere", "cosine/hemisphere", "cosine/sphere", "disk", "triangle", "square", "power"])
def test_accepts_right_samplers(sample, pdf, domain, ires):
    result = stats.chi2_test(sample, pdf, domain, ires=ires, seed=11, test_count=ACCEPT_COUNT)
    assert result.passed, result.message
    assert 0 < result.p_value <= 1 and result.dof > 90
    assert result.histogram.sum() == 1_000_000
    assert abs(result.expected.sum() / 1_000_000 - 1) < 1e-3


@pytest.mark.parametrize("sample,pdf,domain", [
    (warp.square_to_uniform_sphere, warp.square_to_cosine_hemisphere_pdf, "sphere"),
    (warp.square_to_cosine_hemisphere, cos2_pdf, "hemisphere"),
    (disk_r_equals_u, warp.square_to_uniform_disk_pdf, "disk"),
    (lambda u: warp.square_to_cosine_power_hemisphere(u, 10.0),
     lambda d: warp.square_to_cosine_power_hemisphere_pdf(d, 11.0), "hemisphere"),
    (warp.square_to_uniform_disk_concentric,
     lambda p: warp.square_to_uniform_disk_pdf(p) * (1 + 0.05 * p[:, 0]), "disk"),
], ids=["uniform-vs-cosine", "cosine-vs-cos2", "disk-r=u", "power-n-vs-n+1", "5%-tilt"])
def test_rejects_wrong_samplers(sample, pdf, domain):
    result = stats.chi2_test(sample, pdf, domain, seed=11)
    assert not result.passed
    assert not bool(result)
    assert "REJECTED" in result.message or "FAILED" in result.message


@pytest.mark.parametrize("sample,pdf,domain", [
    (warp.square_to_uniform_sphere, warp.square_to_uniform_sphere_pdf, "sphere"),
    (warp.square_to_cosine_hemisphere, warp.square_to_cosine_hemisphere_pdf, "hemisphere"),
    (warp.square_to_uniform_disk_concentric, warp.square_to_uniform_disk_pdf, "disk"),
], ids=["sphere", "cosine", "disk"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_finds_a_density_2_percent_off_on_part_of_the_domain(sample, pdf, domain, seed):
    """The power the suite's tests rely on, at their sample count (10^6):
    a density 2 % too high where x > 0.5 (a fifth to a third of the domain)
    is rejected; the multi-resolution test sees it in its coarse levels,
    where a single fine histogram misses it (caught 0-1 times in 20 seeds
    on each of these samplers, against 20 of 20)."""
    wrong = stats.chi2_test(sample, lambda p: pdf(p) * np.where(p[:, 0] > 0.5, 1.02, 1.0),
                            domain, seed=seed)
    assert not wrong.passed, wrong.message


def test_explains_samples_outside_the_domain():
    result = stats.chi2_test(warp.square_to_uniform_sphere, warp.square_to_uniform_sphere_pdf,
                             "hemisphere", n=10_000)
    assert not result.passed
    assert "outside the domain" in result.message


def test_explains_pdf_not_normalised_negative_or_nan():
    sample, pdf = warp.square_to_uniform_disk, warp.square_to_uniform_disk_pdf
    r = stats.chi2_test(sample, lambda p: 2 * pdf(p), "disk", n=10_000)
    assert not r.passed and "integrates to 2.0" in r.message and "not 1" in r.message
    r = stats.chi2_test(sample, lambda p: pdf(p) - 0.5, "disk", n=10_000)
    assert not r.passed and "negative" in r.message
    r = stats.chi2_test(sample, lambda p: np.where(p[:, 0] > 0.9, np.nan, pdf(p)), "disk",
                        n=10_000)
    assert not r.passed and "NaN" in r.message
    r = stats.chi2_test(lambda u: np.full((len(u), 2), np.nan), pdf, "disk", n=10_000)
    assert not r.passed and "NaN or infinite" in r.message


def test_explains_non_unit_directions():
    r = stats.chi2_test(lambda u: 2 * warp.square_to_uniform_sphere(u),
                        warp.square_to_uniform_sphere_pdf, "sphere", n=10_000)
    assert not r.passed and "not unit vectors" in r.message


def test_domains_from_tuples():
    # An interval (a, b) and a rectangle ((x0, x1), (y0, y1)).
    r = stats.chi2_test(lambda u: 2 + 3 * u[:, 0], lambda x: np.full(len(x), 1 / 3), (2, 5),
                        sample_dim=1, seed=2)
    assert r.passed, r.message
    r = stats.chi2_test(lambda u: u * [2, 1] - [1, 0], lambda p: np.full(len(p), 0.5),
                        ((-1, 1), (0, 1)), seed=2)
    assert r.passed, r.message
    with pytest.raises(ValueError, match="domain"):
        stats.make_domain("torus")


def test_sidak_correction_lowers_the_threshold():
    r1 = stats.chi2_test(warp.square_to_uniform_disk, warp.square_to_uniform_disk_pdf, "disk",
                         n=10_000)
    r10 = stats.chi2_test(warp.square_to_uniform_disk, warp.square_to_uniform_disk_pdf, "disk",
                          n=10_000, test_count=10)
    assert r10.significance < r1.significance == pytest.approx(0.01)
    assert r10.significance == pytest.approx(1 - 0.99 ** 0.1)


def test_two_sample_test_against_numpy(rng):
    a = warp.square_to_cosine_hemisphere(mcs.uniform(200_000, seed=1))
    # An independent cosine sampler written with numpy (polar form).
    u = rng.random((150_000, 2))
    r, phi = np.sqrt(1 - u[:, 1]), 2 * np.pi * u[:, 0]
    b = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(u[:, 1])], axis=1)
    same = stats.two_sample_test(a, b, "hemisphere")
    assert same.passed, same.message
    c = warp.square_to_uniform_hemisphere(mcs.uniform(150_000, seed=2))
    different = stats.two_sample_test(a, c, "hemisphere")
    assert not different.passed


def test_image_metrics(rng):
    ref = rng.random((32, 32, 3)) + 0.5
    assert stats.mse(ref, ref) == 0
    assert stats.mse(ref + 0.1, ref) == pytest.approx(0.01)
    assert stats.relmse(2 * ref, ref, eps=0) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="same shape"):
        stats.mse(ref, ref[:16])


def test_image_ztest_accepts_agreement_and_rejects_bias(rng):
    truth = rng.random((64, 64))
    var = np.full(truth.shape, 0.01)
    a = truth + rng.normal(0, 0.1, truth.shape)
    b = truth + rng.normal(0, 0.1, truth.shape)
    ok = stats.image_ztest(a, var, b, var)
    assert ok.passed, ok.message
    assert abs(ok.mean_z) < 4 and ok.block_z.shape == (8, 8)
    assert "ZTestResult(passed=True" in repr(ok) and "array((8, 8)" in repr(ok)
    # A bias everywhere: the image mean's SE is 0.1 sqrt(2) / 64 = 0.0022.
    biased = stats.image_ztest(a + 0.02, var, b, var)
    assert not biased.passed and "whole-image means differ" in biased.message
    # A bias in one block only: 0.1 sqrt(2) / 8 = 0.018 SE per block.
    local = a.copy()
    local[8:16, 24:32] += 0.12
    t = stats.image_ztest(local, var, b, var)
    assert not t.passed and "block (1, 3)" in t.message
    shifted = np.roll(b, 1, axis=1)
    assert stats.image_ztest(a, var, shifted, var).passed  # noise 10x the signal's change
    with pytest.raises(ValueError, match="infinite"):
        stats.image_ztest(a, np.full(a.shape, np.inf), b, var)


def test_luminance_is_rec709():
    rgb = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]])
    np.testing.assert_allclose(stats.luminance(rgb), [0.2126, 0.7152, 0.0722, 1.0])
    with pytest.raises(ValueError, match="RGB"):
        stats.luminance(np.ones((4, 5)))


class _Render:
    def __init__(self, luminance, variance):
        self.luminance, self.luminance_variance = luminance, variance


def test_render_ztest_compares_noise_free_pixels_by_tolerance(rng):
    truth = rng.random((32, 32)) + 0.5
    var = np.full(truth.shape, 1e-4)
    var[:8] = 0.0                         # a noise-free band (seen sky)
    a = truth + rng.normal(0, 1e-2, truth.shape) * (var > 0)
    b = truth + rng.normal(0, 1e-2, truth.shape) * (var > 0)
    b[:8] *= 1 + 1e-5                     # float32 rounding there
    t = stats.render_ztest(_Render(a, var), _Render(b, var))
    assert t.passed, t.message
    assert t.z.shape == truth.shape and np.all(t.z[:8] == 0)
    # The noise-free band (the first row of 8x8 blocks) is left out of the
    # z-tests rather than deflating them.
    assert np.all(np.isnan(t.block_z[0])) and np.all(np.isfinite(t.block_z[1:]))
    b[:8] *= 1.01
    t = stats.render_ztest(_Render(a, var), _Render(b, var))
    assert not t.passed and "noise-free" in t.message


def test_image_ztest_takes_region_variances_from_runs():
    """Images whose neighbouring pixels share noise (each run a 5 x 5 box
    blur of white noise, as a splatting filter shares samples): the sum of
    pixel variances underestimates a block's by ~25x, so the plain test
    rejects two unbiased estimates; with the runs it accepts them at its
    nominal rate (50 seeds, at most 2 rejections at alpha 0.01) and still
    finds a bias of 0.2 standard deviations of a pixel."""
    from scipy.ndimage import uniform_filter

    def case(seed, bias=0.0):
        g = np.random.default_rng(seed)
        runs = np.stack([uniform_filter(g.normal(size=(64, 64)), 5, mode="wrap") * 5
                         for _ in range(16)]) + bias
        a = g.normal(size=(64, 64)) * 0.3
        b = runs.mean(axis=0)
        vb = runs.var(axis=0, ddof=1) / 16
        return a, np.full_like(a, 0.09), b, vb, runs

    a, va, b, vb, runs = case(0)
    assert not stats.image_ztest(a, va, b, vb).passed
    rejected = sum(not stats.image_ztest(*case(s)[:4], runs_b=case(s)[4], alpha=0.01).passed
                   for s in range(50))
    assert rejected <= 2, rejected
    a, va, b, vb, runs = case(1, bias=0.2)
    t = stats.image_ztest(a, va, b, vb, runs_b=runs)
    assert not t.passed and t.mean_z < -4, t.message
    # The same with the runs on the other side (the sign turns).
    assert stats.image_ztest(b, vb, a, va, runs_a=runs).mean_z > 4
    with pytest.raises(ValueError, match=r"runs_b must be \(R, H, W\)"):
        stats.image_ztest(a, va, b, vb, runs_b=runs[:, :3])
    with pytest.raises(ValueError, match="runs_b must be"):
        stats.image_ztest(a, va, b, vb, runs_b=runs[:1])
