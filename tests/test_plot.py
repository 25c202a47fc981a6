"""mcsample.plot draws what it is given (checked on the artists' data), returns
Figures / Axes, never calls plt.show(), and leaves matplotlib out of
``import mcsample``."""

import subprocess
import sys

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

import mcsample as mcs  # noqa: E402
from mcsample import plot, stats, warp  # noqa: E402


@pytest.fixture(autouse=True)
def no_show(monkeypatch):
    """Fails a test whose plot calls plt.show(); closes its figures."""
    def show(*args, **kwargs):
        raise AssertionError("mcsample.plot called plt.show()")

    monkeypatch.setattr(plt, "show", show)
    yield
    plt.close("all")


def test_import_mcsample_does_not_import_matplotlib():
    code = ("import sys, mcsample, mcsample.plot; "
            "assert 'matplotlib' not in sys.modules, 'matplotlib imported'")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_tonemap_is_srgb_of_exposed_clipped_values():
    x = np.array([[0.0, 0.0031308, 0.18, 1.0, 4.0, np.nan]])
    t = plot.tonemap(x)
    expected = [0.0, 12.92 * 0.0031308, 1.055 * 0.18 ** (1 / 2.4) - 0.055, 1.0, 1.0, 0.0]
    np.testing.assert_allclose(t[0], expected, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(plot.tonemap(x[:, :3] / 4, exposure=2), t[:, :3], rtol=1e-12)


def test_image_shows_the_tonemapped_image():
    img = np.random.default_rng(0).random((4, 5, 3)).astype(np.float32) * 3
    ax = plot.image(img, exposure=-1)
    assert isinstance(ax, Axes)
    np.testing.assert_allclose(ax.get_images()[0].get_array(), plot.tonemap(img, -1))


@pytest.mark.parametrize("domain, sampler", [
    ("disk", warp.square_to_uniform_disk_concentric),
    ("square", warp.square_to_uniform_triangle),
    ("hemisphere", warp.square_to_cosine_hemisphere),
    ("sphere", warp.square_to_uniform_sphere),
])
def test_samples_flat_scatter_is_in_the_domain_parameters(domain, sampler):
    pts = sampler(mcs.uniform(500, 2, seed=3))
    ax = plot.samples(pts, domain)
    xy = ax.collections[0].get_offsets()
    if domain in ("disk", "square"):
        np.testing.assert_allclose(xy, pts)
    else:  # unrolled to (phi, cos theta)
        np.testing.assert_allclose(xy[:, 1], pts[:, 2], atol=1e-12)
        np.testing.assert_allclose(xy[:, 0], np.arctan2(pts[:, 1], pts[:, 0]), atol=1e-12)


def test_samples_3d_and_thinning():
    pts = warp.square_to_uniform_sphere(mcs.uniform(10_000, 2, seed=4))
    ax = plot.samples(pts, "sphere", projection="3d", max_points=1000)
    assert ax.name == "3d"
    x, y, z = ax.collections[-1]._offsets3d
    assert len(x) == 1000
    np.testing.assert_allclose(np.asarray(x) ** 2 + np.asarray(y) ** 2 + np.asarray(z) ** 2,
                               1.0, atol=1e-9)
    with pytest.raises(ValueError, match="projection"):
        plot.samples(pts, "square", projection="3d")


def test_chi2_draws_histogram_expected_and_difference():
    result = stats.chi2_test(warp.square_to_cosine_hemisphere,
                             lambda d: warp.square_to_cosine_power_hemisphere_pdf(d, 1.5),
                             "hemisphere", n=100_000)
    assert not result.passed
    fig = plot.chi2(result)
    assert isinstance(fig, Figure)
    images = [ax.get_images()[0].get_array() for ax in fig.axes[:3]]
    np.testing.assert_allclose(images[0], result.histogram)
    np.testing.assert_allclose(images[1], result.expected)
    np.testing.assert_allclose(images[2], result.histogram - result.expected)
    assert "FAILED" in fig.axes[2].get_title()


def test_chi2_on_an_interval_draws_bars():
    result = stats.chi2_test(lambda u: warp.interval_to_power(u[:, 0], 3.0),
                             lambda x: warp.interval_to_power_pdf(x, 3.0), "interval",
                             n=50_000)
    fig = plot.chi2(result)
    heights = [p.get_height() for p in fig.axes[0].patches]
    np.testing.assert_allclose(heights, result.histogram[0])


def test_distribution_draws_pmf_and_cdf():
    d = mcs.Discrete1D([0.2, 0.3, 0.4, 0.1])
    fig = plot.distribution(d)
    np.testing.assert_allclose([p.get_height() for p in fig.axes[0].patches], d.pmf())
    np.testing.assert_allclose(fig.axes[1].lines[0].get_ydata()[1:-1], np.cumsum(d.pmf()))
    pc = mcs.PiecewiseConstant1D([1.0, 3.0], a=0.0, b=2.0)
    fig = plot.distribution(pc)
    np.testing.assert_allclose(fig.axes[1].lines[0].get_ydata()[[0, -1]], [0.0, 1.0])
    fig = plot.distribution(mcs.Discrete2D([[1.0, 2.0], [3.0, 4.0]]))
    np.testing.assert_allclose([p.get_height() for p in fig.axes[1].patches], [0.3, 0.7])


def _one_hot(mapping: str) -> mcs.EnvMap:
    shape = {"latlong": (16, 32, 3), "angular": (32, 32, 3), "cube": (6, 8, 8, 3)}[mapping]
    img = np.zeros(shape, dtype=np.float32)
    index = {"latlong": (5, 20), "angular": (10, 12), "cube": (4, 3, 5)}[mapping]
    img[index] = 100.0
    return mcs.EnvMap(img, mapping=mapping)


@pytest.mark.parametrize("mapping", ["latlong", "angular", "cube"])
def test_envmap_density_sums_to_one_and_samples_land_on_the_light(mapping):
    # A smooth sky (bright toward +Y and +X), so that the display's
    # midpoint sum is an accurate integral.
    v, u = np.meshgrid(np.linspace(0, 1, 64), np.linspace(0, 1, 128), indexing="ij")
    smooth = (1.5 + np.cos(np.pi * v) + 0.5 * np.sin(2 * np.pi * u))[..., None] * [1, 1, 1]
    env = mcs.EnvMap(smooth.astype(np.float32)).convert(
        mapping, {"latlong": (64, 128), "angular": 96, "cube": 32}[mapping])
    fig = plot.envmap(env, n_samples=500)
    density = np.asarray(fig.axes[1].get_images()[0].get_array().filled(0.0))
    # Probability per display pixel: the map-plane density (pdf times the
    # mapping's Jacobian) integrates to 1.
    assert abs(density.sum() - 1.0) < 0.01
    one_hot = _one_hot(mapping)
    fig = plot.envmap(one_hot, n_samples=200)
    xy = fig.axes[2].collections[0].get_offsets()
    assert len(xy) == 200
    shown = fig.axes[0].get_images()[0].get_array()
    lit = np.argwhere(shown[..., :3].sum(-1) > 0)
    # Every sample falls on the bright texel's pixel, within the reach of
    # the bilinear filter and of the sampling table's cells (2 pixels); a
    # face or an axis out of place in the layout would be far off.
    dist = np.abs(np.floor(xy[:, ::-1])[:, None, :] - lit[None, :, :]).max(-1).min(-1)
    assert dist.max() <= 2


def test_envmap_rejects_unknown_density():
    with pytest.raises(ValueError, match="density"):
        plot.envmap(mcs.EnvMap(), density="steradian")


def test_phong_lobe_peaks_at_the_mirror_direction():
    theta_i = np.radians(40)
    wi = [np.sin(theta_i), 0.0, np.cos(theta_i)]
    ax = plot.phong_lobe(wi, exponents=(10, 1000), quantity="pdf")
    for line in ax.lines[:2]:
        angle, value = line.get_xdata(), line.get_ydata()
        assert abs(angle[np.argmax(value)] + theta_i) < 0.01
        assert value.max() == pytest.approx(1.0)
    wide, sharp = (np.count_nonzero(line.get_ydata() > 0.5) for line in ax.lines[:2])
    assert sharp < wide


def test_convergence_draws_the_inverse_sqrt_slope():
    n = np.array([10, 100, 1000, 10_000])
    ax = plot.convergence(n, {"uniform": 2 / np.sqrt(n), "cosine": 0.5 / np.sqrt(n)})
    ref = ax.lines[-1]
    slope = np.diff(np.log(ref.get_ydata())) / np.diff(np.log(ref.get_xdata()))
    np.testing.assert_allclose(slope, -0.5)
    assert ref.get_ydata()[0] == pytest.approx(2 / np.sqrt(10))
    with pytest.raises(ValueError, match="shape"):
        plot.convergence(n, [1.0, 2.0])


def test_error_maps_have_colour_bars_and_right_values():
    rng = np.random.default_rng(5)
    ref = rng.random((6, 7, 3)) + 0.5
    img = ref * 1.1
    ax = plot.error_map(img, ref, kind="relative", eps=0.0)
    np.testing.assert_allclose(ax.get_images()[0].get_array(), 0.1, rtol=1e-9)
    assert len(ax.figure.axes) == 2  # the map and its colour bar
    lum, var = ref[..., 0], np.full((6, 7), 0.01)
    ax = plot.error_map(lum + 0.2, lum, kind="z", variance=var, reference_variance=var)
    np.testing.assert_allclose(ax.get_images()[0].get_array(), 0.2 / np.sqrt(0.02))
    with pytest.raises(ValueError, match="variance"):
        plot.error_map(lum, lum, kind="z")
    with pytest.raises(ValueError, match="luminance"):
        plot.error_map(ref, ref, kind="z", variance=ref)
    with pytest.raises(ValueError, match="kind"):
        plot.error_map(ref, ref, kind="squared")


def test_compare_lays_out_images_above_error_maps():
    ref = np.ones((8, 16, 3))
    fig = plot.compare({"a": ref * 1.2, "b": ref}, ref)
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert titles[0].startswith("a") and "relMSE" in titles[0]
    assert len([ax for ax in fig.axes if ax.get_images()]) == 4


def test_cube_cross_is_seamless():
    layout = plot._EnvLayout(mcs.EnvMap().convert("cube", 16))
    dirs, valid, _ = layout.pixel_directions()
    # Neighbouring pixels of the cross, also across face edges, show
    # neighbouring directions (a pixel spans at most ~0.13 rad here).
    for axis in (0, 1):
        a, b = np.swapaxes(dirs, 0, axis)[:-1], np.swapaxes(dirs, 0, axis)[1:]
        both = np.swapaxes(valid, 0, axis)[:-1] & np.swapaxes(valid, 0, axis)[1:]
        angle = np.arccos(np.clip((a * b).sum(-1), -1, 1))[both]
        assert angle.max() < 0.15
