"""The Phong BRDF: sample against pdf (chi-square on the whole sphere, in
the frame of the mirror direction so that sharp lobes are resolved), mean
weight = directional albedo by quadrature, eval/pdf conventions."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats

EXPONENTS = [0.0, 1.0, 10.0, 100.0, 1000.0]
ANGLES = [0.0, 80.0, 89.0]  # wi: at the normal, grazing
# Zoom of the sphere domain toward the lobe axis, and integration points.
ZOOM = {0.0: 1.0, 1.0: 1.0, 10.0: 2.0, 100.0: 3.0, 1000.0: 4.0}
IRES = {0.0: 4, 1.0: 4, 10.0: 8, 100.0: 16, 1000.0: 16}
TEST_COUNT = len(EXPONENTS) * len(ANGLES)


def _wi(degrees):
    t = np.radians(degrees)
    return np.array([np.sin(t), 0.0, np.cos(t)])


def _material(n):
    return mcs.Phong([0.2, 0.3, 0.1], [0.7, 0.5, 0.6], n)


def _mirror(wi):
    return np.array([-wi[0], -wi[1], wi[2]])


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("n", EXPONENTS)
def test_chi2_sample_against_pdf_on_the_sphere(n, angle):
    phong, wi = _material(n), _wi(angle)
    frame = mcs.Frame(_mirror(wi))  # the lobe's axis becomes +z
    result = stats.chi2_test(
        lambda u: frame.to_local(phong.sample(wi, u).wo),
        lambda d: phong.pdf(wi, frame.to_world(d)),
        stats.SphericalDomain(ZOOM[n]), n=1_000_000, sample_dim=3, ires=IRES[n], seed=7,
        test_count=TEST_COUNT)
    assert result.passed, result.message


def test_chi2_rejects_a_wrong_exponent_in_the_pdf():
    phong, wi = _material(100.0), _wi(30.0)
    wrong = mcs.Phong([0.2, 0.3, 0.1], [0.7, 0.5, 0.6], 110.0)
    frame = mcs.Frame(_mirror(wi))
    result = stats.chi2_test(lambda u: frame.to_local(phong.sample(wi, u).wo),
                             lambda d: wrong.pdf(wi, frame.to_world(d)),
                             stats.SphericalDomain(3.0), sample_dim=3, ires=16, seed=7)
    assert not result.passed


def _albedo(phong, wi, zoom=4.0, nphi=2048, ny=4096):
    """∫ f_r(wi, wo) cos θo dωo by the midpoint rule on the sphere around the
    mirror direction (zoomed so that the lobe is resolved)."""
    dom = stats.SphericalDomain(zoom)
    frame = mcs.Frame(_mirror(wi))
    phi = -np.pi + (np.arange(nphi) + 0.5) * (2 * np.pi / nphi)
    y = -1 + (np.arange(ny) + 0.5) * (2.0 / ny)
    xy = np.stack(np.meshgrid(phi, y), -1).reshape(-1, 2)
    wo = frame.to_world(dom.from_param(xy))
    f = phong.eval(wi, wo) * np.maximum(wo[:, 2], 0)[:, None]
    return (f * np.asarray(dom.jacobian(xy)).reshape(-1, 1)).sum(axis=0) * (2 * np.pi / nphi) * (2.0 / ny)


@pytest.mark.parametrize("angle", [0.0, 60.0, 89.0])
@pytest.mark.parametrize("n", [1.0, 100.0, 1000.0])
def test_mean_weight_is_the_directional_albedo(n, angle):
    phong, wi = _material(n), _wi(angle)
    s = phong.sample(wi, mcs.uniform(1_000_000, 3, seed=4))
    mean = s.weight.mean(axis=0)
    stderr = s.weight.std(axis=0) / np.sqrt(len(s.weight))
    albedo = _albedo(phong, wi)
    assert np.all(np.abs(mean - albedo) < 5 * stderr + 1e-4), (mean, albedo, stderr)
    # Energy conservation: the albedo never exceeds diffuse + specular.
    assert np.all(albedo <= np.array([0.9, 0.8, 0.7]) + 1e-3)


def test_eval_pdf_conventions():
    phong = _material(20.0)
    wi = _wi(30.0)
    r = _mirror(wi)
    f = phong.eval(wi, r)
    expected = np.array([0.2, 0.3, 0.1]) / np.pi + np.array([0.7, 0.5, 0.6]) * 22 / (2 * np.pi)
    assert np.allclose(f, expected, rtol=1e-12)
    assert np.array_equal(phong.eval(wi, [0, 0, -1.0]), np.zeros(3))
    assert np.array_equal(phong.eval([0, 0.6, -0.8], r), np.zeros(3))
    pd = phong.diffuse_probability
    assert pd == pytest.approx(0.3 / (0.3 + 0.7))
    assert phong.pdf(wi, r) == pytest.approx(pd * r[2] / np.pi + (1 - pd) * 21 / (2 * np.pi))
    # Below the surface the lobe still has density where it reaches there.
    grazing = _wi(89.0)
    below = np.array([-np.sin(np.radians(91.0)), 0, np.cos(np.radians(91.0))])
    assert phong.pdf(grazing, below) > 0
    # Batches: a single wi broadcasts against u; components and dtypes.
    s = phong.sample(wi, mcs.uniform(10_000, 3, seed=1))
    assert s.wo.shape == (10_000, 3) and s.pdf.shape == (10_000,) and s.weight.shape == (10_000, 3)
    assert s.component.dtype == np.int64 and set(np.unique(s.component)) == {0, 1}
    assert abs(np.mean(s.component == 0) - pd) < 0.02
    assert np.allclose(s.pdf, phong.pdf(wi, s.wo))
    s32 = phong.sample(wi, mcs.uniform(100, 3, seed=1, dtype=np.float32))
    assert s32.wo.dtype == np.float32 and s32.weight.dtype == np.float32
    one = phong.sample(wi, [0.3, 0.4, 0.9])
    assert one.wo.shape == (3,) and np.ndim(one.pdf) == 0


def test_selection_rules():
    max_rule = mcs.Phong([0.1, 0.1, 0.4], [0.2, 0.3, 0.1], 5.0)
    assert max_rule.diffuse_probability == pytest.approx(0.4 / (0.4 + 0.3))
    lum = mcs.Phong([0.1, 0.1, 0.4], [0.2, 0.3, 0.1], 5.0, selection="luminance")
    y = lambda c: 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]  # noqa: E731
    yd, ys = y([0.1, 0.1, 0.4]), y([0.2, 0.3, 0.1])
    assert lum.diffuse_probability == pytest.approx(yd / (yd + ys))
    grey = mcs.Phong(0.25, 0.5, 3.0)
    assert grey.diffuse == [0.25] * 3 and grey.diffuse_probability == pytest.approx(1 / 3)


def test_black_material_has_zero_weight_never_nan():
    black = mcs.Phong(0.0, 0.0, 10.0)
    s = black.sample(_wi(45.0), mcs.uniform(1000, 3, seed=2))
    assert np.all(s.weight == 0) and np.all(np.isfinite(s.pdf))
