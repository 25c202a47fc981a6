"""EnvMap on its own: conventions of the three mappings, samples against
their own pdf (chi-square), pdf(sample) = sample.pdf and weight = eval / pdf,
densities that integrate to 1, pdf > 0 wherever eval > 0, the all-black map,
conversion between mappings, files and the packaged sky."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats

SKY = mcs.EnvMap()


def one_hot(mapping, x, y, size=(9, 16)):
    """A black map with one bright texel (x, y)."""
    h, w = size
    if mapping == "cube":
        image = np.zeros((6, w, w, 3), np.float32)
        image[y // w, y % w, x] = [10.0, 20.0, 5.0]
    else:
        image = np.zeros((h, w, 3), np.float32)
        image[y, x] = [10.0, 20.0, 5.0]
    return mcs.EnvMap(image, mapping=mapping)


def integrate(env, f):
    return mcs.estimators.envmap_integral(env, f)


def sphere_grid(n_phi=720, n_z=720):
    """Midpoints of an equal-area (phi, z) grid, and the solid angle of a
    cell."""
    phi = (np.arange(n_phi) + 0.5) / n_phi * 2 * np.pi
    z = -1 + (np.arange(n_z) + 0.5) / n_z * 2
    phi, z = np.meshgrid(phi, z)
    r = np.sqrt(1 - z**2)
    d = np.stack([r * np.cos(phi), z, r * np.sin(phi)], -1).reshape(-1, 3)
    return d, 4 * np.pi / (n_phi * n_z)


ROTATION = np.array([[0.8, 0.0, 0.6], [0.0, 1.0, 0.0], [-0.6, 0.0, 0.8]])

MAPS = {
    "sky": SKY,
    "sky rotated x3": mcs.EnvMap(SKY.image, to_world=ROTATION, scale=3.0),
    "sky mitsuba mode": mcs.EnvMap(SKY.image, sampling="mitsuba"),
    "sky piecewise": mcs.EnvMap(SKY.image, sampling="piecewise"),
    "one-hot latlong piecewise": mcs.EnvMap(one_hot("latlong", 5, 3).image, sampling="piecewise"),
    "sky compensated": mcs.EnvMap(SKY.image, compensate=True),
    "sky angular": SKY.convert("angular", 256),
    "sky cube": SKY.convert("cube", 64),
    "one-hot latlong": one_hot("latlong", 5, 3),
    "one-hot angular": one_hot("angular", 4, 11, (16, 16)),
    "one-hot cube": one_hot("cube", 2, 13, (24, 4)),
}


def test_latlong_axes_are_mitsubas():
    d = np.array([[0, 0, -1], [1, 0, 0], [0, 0, 1], [0, 1, 0], [0, -1, 0.0]])
    uv = SKY.dir_to_uv(d)
    np.testing.assert_allclose(uv[:3], [[0, 0.5], [0.25, 0.5], [0.5, 0.5]], atol=1e-15)
    assert uv[3, 1] == 0 and uv[4, 1] == 1
    np.testing.assert_allclose(SKY.uv_to_dir(uv[:3]), d[:3], atol=1e-15)
    # Texel columns centred at (x + 1/2) / W, rows on v = y / (H - 1).
    image = SKY.image
    h, w, _ = image.shape
    np.testing.assert_allclose(SKY.eval(SKY.uv_to_dir([(7.5) / w, 5 / (h - 1)])), image[5, 7],
                               rtol=1e-6)


def test_angular_and_cube_conventions():
    probe = SKY.convert("angular", 64)
    np.testing.assert_allclose(probe.uv_to_dir([[0.5, 0.5], [0.5, 0.25], [0.75, 0.5]]),
                               [[0, 0, 1], [0, 1, 0], [1, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(probe.dir_to_uv([0, 0, 1.0]), [0.5, 0.5])
    assert probe.image.shape == (64, 64, 3)
    # Outside the circle there is no light.
    assert np.all(probe.image[0, 0] == 0)
    cube = SKY.convert("cube", 16)
    assert cube.image.shape == (6, 16, 16, 3)
    centres = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
    uv = cube.dir_to_uv(np.array(centres, float))
    np.testing.assert_allclose(uv, [[0.5, f + 0.5] for f in range(6)], atol=1e-15)
    # The +Z face looks upright: its top row is toward +Y, its left column
    # toward -X.
    top, left = cube.uv_to_dir([[0.5, 4.0], [0.0, 4.5]])
    assert top[1] > 0.5 and left[0] < -0.5


@pytest.mark.parametrize("name", list(MAPS))
def test_samples_follow_their_own_pdf(name):
    """In the table's own coordinates, with histogram cells inside the
    table's cells, the expected counts of a piecewise map are exact; the
    luminance and Mitsuba's bilinear densities vary within cells and are
    checked on the sphere, with expected counts by jittered (unbiased)
    integration."""
    env = MAPS[name]
    if env.sampling != "piecewise":
        domain, res, ires, integration = "sphere", 51, 8, "jittered"
    else:
        domain = stats.EnvMapDomain(env)
        res, ires, integration = domain.cells, 4, "trapezoid"
    result = stats.chi2_test(lambda u: env.sample(u).direction, env.pdf, domain,
                             res=res, ires=ires, integration=integration,
                             test_count=2 * len(MAPS))
    assert result.passed, result.message


@pytest.mark.parametrize("name", ["sky", "sky rotated x3"])
def test_samples_follow_their_own_pdf_on_the_sphere(name):
    """The same on a sphere histogram whose cells cut across the table's,
    where the density steps inside cells: expected counts by jittered
    (unbiased) integration."""
    env = MAPS[name]
    result = stats.chi2_test(lambda u: env.sample(u).direction, env.pdf, "sphere",
                             res=51, ires=8, integration="jittered",
                             test_count=2 * len(MAPS))
    assert result.passed, result.message


def _coarse_map():
    """A 7 x 12 lat-long map of random texels, a fifth of them black: cells
    of 30 degrees, which a 51 x 51 sphere histogram resolves inside."""
    rng = np.random.default_rng(3)
    image = 5 * rng.random((7, 12, 3)) ** 3
    image[rng.random((7, 12)) < 0.2] = 0
    return mcs.EnvMap(image)


FLOAT32_MAPS = {"sky": SKY, "sky rotated x3": MAPS["sky rotated x3"],
                "one-hot latlong": MAPS["one-hot latlong"], "coarse": _coarse_map()}


@pytest.mark.parametrize("name", list(FLOAT32_MAPS))
def test_float32_samples_follow_their_own_float32_pdf(name):
    """float32 draws of the luminance density are placed in their cells in
    float32, from the float32 table that pdf reads in float32: their
    directions against float32 pdf on a sphere histogram that resolves the
    coarse map's cells inside (jittered, unbiased integration), and each
    draw's pdf against pdf(direction) and its weight against eval / pdf."""
    env = FLOAT32_MAPS[name]
    result = stats.chi2_test(
        lambda u: env.sample(u.astype(np.float32)).direction.astype(np.float64),
        lambda d: env.pdf(d.astype(np.float32)).astype(np.float64), "sphere",
        res=51, ires=8, integration="jittered", test_count=len(FLOAT32_MAPS))
    assert result.passed, result.message
    s = env.sample(mcs.uniform(200_000, 2, seed=7).astype(np.float32))
    assert np.all(s.pdf > 0)
    # A float32 direction lands an ulp away from its point, where a steep
    # cell (the sun's rim) moves the density by up to ~1e-4.
    same = np.isclose(env.pdf(s.direction), s.pdf, rtol=1e-3)
    assert same.mean() > 0.9999
    np.testing.assert_allclose((s.weight * s.pdf[:, None])[same], env.eval(s.direction)[same],
                               rtol=2e-3, atol=1e-6)


@pytest.mark.parametrize("name", list(MAPS))
def test_pdf_of_samples_and_weights(name):
    env = MAPS[name]
    s = env.sample(mcs.uniform(200_000, 2, seed=7))
    assert np.allclose(np.linalg.norm(s.direction, axis=1), 1, atol=1e-12)
    assert np.all(s.pdf > 0)
    # Only samples within round-off of a cell boundary may find the next cell.
    same = np.isclose(env.pdf(s.direction), s.pdf, rtol=1e-6)
    assert same.mean() > 0.9999
    np.testing.assert_allclose((s.weight * s.pdf[:, None])[same], env.eval(s.direction)[same],
                               rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_pdf_ignores_the_length_of_directions(dtype):
    d = SKY.sample(mcs.uniform(10_000, 2, seed=3)).direction.astype(dtype)
    scaled = d * np.linspace(0.01, 100, len(d), dtype=dtype)[:, None]
    # The sky's density follows its radiance within texels: a float32
    # direction, normalised, lands an ulp away, where the sun's slope moves
    # the density by up to ~1e-4.
    np.testing.assert_allclose(SKY.pdf(scaled), SKY.pdf(d), rtol=1e-5 if dtype == np.float64 else 5e-4)
    # A zero vector has no direction: density 0, not NaN.
    assert np.array_equal(SKY.pdf(np.zeros((3, 3), dtype)), np.zeros(3, dtype))


@pytest.mark.parametrize("name", list(MAPS))
def test_pdf_integrates_to_one(name):
    env = MAPS[name]
    assert abs(integrate(env, env.pdf) - 1) < 1e-9
    # And on a plain (phi, cos theta) grid, where the sun is resolved worse.
    d, cell = sphere_grid()
    assert abs(env.pdf(d).sum() * cell - 1) < 0.1


@pytest.mark.parametrize("mapping,texels", [
    ("latlong", [(5, 3), (0, 0), (15, 8), (8, 0)]),
    ("angular", [(4, 11), (0, 8), (8, 8), (15, 7)]),
    ("cube", [(2, 13), (0, 0), (3, 23)]),
])
def test_one_hot_maps_are_covered_and_unbiased(mapping, texels):
    """Wherever eval > 0, pdf > 0: envmap sampling alone is unbiased, also for
    a texel on a pole, the seam, the rim of a probe or a cube edge."""
    d, cell = sphere_grid(1440, 1440)
    size = (24, 4) if mapping == "cube" else ((16, 16) if mapping == "angular" else (9, 16))
    for x, y in texels:
        env = one_hot(mapping, x, y, size)
        lit = env.eval(d)[:, 1] > 0
        assert lit.any()
        assert np.all(env.pdf(d[lit]) > 0), (mapping, x, y)
        truth = env.eval(d).sum(0) * cell
        w = env.sample(mcs.uniform(400_000, 2, seed=x + 7 * y)).weight
        mean, err = w.mean(0), w.std(0) / np.sqrt(len(w))
        assert np.all(np.abs(mean - truth) < 4 * err + 2e-3 * truth), (mapping, x, y, mean, truth)


def test_black_maps_sample_nothing():
    for env in [mcs.EnvMap(np.zeros((8, 16, 3))), mcs.EnvMap(SKY.image, scale=0.0),
                mcs.EnvMap(np.zeros((6, 4, 4, 3)), mapping="cube")]:
        s = env.sample(mcs.uniform(1000, 2))
        assert np.all(s.pdf == 0) and np.all(s.weight == 0)
        np.testing.assert_allclose(np.linalg.norm(s.direction, axis=1), 1)
        assert np.all(env.pdf(s.direction) == 0)


def test_tiny_latlong_maps_are_padded_as_mitsuba_would():
    env = mcs.EnvMap(np.array([[[1.0, 2.0, 3.0]]]))
    assert env.image.shape == (3, 2, 3)
    np.testing.assert_allclose(env.eval([[0.3, -0.4, 0.5], [0, 1, 0]]), [[1, 2, 3]] * 2)


def test_compensation_leaves_dark_directions_to_other_strategies():
    plain, comp = MAPS["sky"], MAPS["sky compensated"]
    ground = np.array([0.3, -0.8, 0.1])
    assert plain.pdf(ground) > 0 and comp.pdf(ground) == 0
    lum = SKY.image @ np.array([0.2126, 0.7152, 0.0722])
    y, x = np.unravel_index(np.argmax(lum), lum.shape)
    sun = SKY.uv_to_dir([(x + 0.5) / lum.shape[1], y / (lum.shape[0] - 1)])
    assert comp.pdf(sun) > plain.pdf(sun) > 0


def test_convert_round_trip_keeps_the_map():
    """latlong -> cube / angular -> latlong within interpolation error: the
    power within 0.5% (1% through a probe, which stretches -Z); texel by texel within 5% wherever the map is smooth
    (away from the sun's rim and the horizon, which the resampling blurs)."""
    from scipy import ndimage

    power = integrate(SKY, SKY.eval)
    lum = SKY.image.sum(-1)
    sky = ndimage.maximum_filter(lum, 5, mode="wrap") < 1.5 * ndimage.minimum_filter(lum, 5, mode="wrap")
    assert sky.mean() > 0.8
    for target, res, rtol in [("cube", 256, 5e-3), ("angular", 512, 1e-2)]:
        back = SKY.convert(target, res).convert("latlong", (128, 256))
        assert back.image.shape == SKY.image.shape
        np.testing.assert_allclose(integrate(back, back.eval), power, rtol=rtol)
        np.testing.assert_allclose(back.image[sky], SKY.image[sky], rtol=0.05, atol=2e-3)


def test_float32_in_float32_out():
    u = mcs.uniform(100, 2).astype(np.float32)
    s = SKY.sample(u)
    assert s.direction.dtype == s.pdf.dtype == s.weight.dtype == np.float32
    assert SKY.eval(s.direction).dtype == np.float32
    np.testing.assert_allclose(s.pdf, SKY.sample(u.astype(np.float64)).pdf, rtol=1e-5)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_out_receives_the_results(dtype):
    u = mcs.uniform(1000, 2, seed=3).astype(dtype)
    fresh = SKY.sample(u)
    outs = (np.empty((1000, 3), dtype), np.empty(1000, dtype), np.empty((1000, 3), dtype))
    s = SKY.sample(u, out=outs)
    assert all(got is out for got, out in zip((s.direction, s.pdf, s.weight), outs))
    for got, want in [(s.direction, fresh.direction), (s.pdf, fresh.pdf), (s.weight, fresh.weight)]:
        assert np.array_equal(got, want)
    pdf, radiance = np.empty(1000, dtype), np.empty((1000, 3), dtype)
    assert SKY.pdf(fresh.direction, out=pdf) is pdf
    assert np.array_equal(pdf, SKY.pdf(fresh.direction))
    assert SKY.eval(fresh.direction, out=radiance) is radiance
    assert np.array_equal(radiance, SKY.eval(fresh.direction))


def test_bad_out_is_refused():
    u = mcs.uniform(10, 2, seed=3)
    d = SKY.sample(u).direction
    with pytest.raises(TypeError, match="dtype float64"):
        SKY.pdf(d, out=np.empty(10, np.float32))
    with pytest.raises(ValueError, match="shape"):
        SKY.eval(d, out=np.empty((10, 2)))
    with pytest.raises(ValueError, match="share memory"):
        SKY.eval(d, out=d)
    with pytest.raises(TypeError, match="tuple of three arrays"):
        SKY.sample(u, out=np.empty((10, 3)))
    shared = np.empty((10, 3))
    with pytest.raises(ValueError, match="share memory"):
        SKY.sample(u, out=(shared, np.empty(10), shared))


def test_single_direction_is_unbatched():
    assert SKY.eval([0, 1, 0]).shape == (3,)
    assert np.ndim(SKY.pdf([0, 1, 0])) == 0
    s = SKY.sample([0.5, 0.5])
    assert s.direction.shape == (3,) and np.ndim(s.pdf) == 0


def test_files_round_trip(tmp_path):
    path = tmp_path / "sky.exr"
    mcs.io.write_exr(path, SKY.image)
    env = mcs.EnvMap.load(path, scale=2.0)
    np.testing.assert_array_equal(env.image, SKY.image)
    assert env.scale == 2.0
    cube = SKY.convert("cube", 8)
    faces = cube.image
    mcs.io.write_exr(tmp_path / "v.exr", faces.reshape(48, 8, 3))
    mcs.io.write_exr(tmp_path / "h.exr", np.concatenate(list(faces), axis=1))
    for name in ["v.exr", "h.exr"]:
        loaded = mcs.EnvMap.load(tmp_path / name, mapping="cube")
        np.testing.assert_array_equal(loaded.image, faces)


def test_radiance_hdr_files(tmp_path):
    """A 4 x 3 RGBE file written by hand (flat scanlines): texels decode to
    mantissa / 256 * 2^(exponent - 128) (the image crate's decoding, without
    Radiance's half-step offset)."""
    pixels = np.array([[[128, 64, 32, 129], [255, 0, 0, 128], [0, 0, 0, 0], [1, 2, 3, 140]]] * 3,
                      np.uint8)
    path = tmp_path / "probe.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3 +X 4\n" + pixels.tobytes())
    env = mcs.EnvMap.load(path)
    expected = pixels[..., :3] / 256 * 2.0 ** (pixels[..., 3:].astype(float) - 128)
    expected[pixels[..., 3] == 0] = 0
    np.testing.assert_allclose(env.image, expected, rtol=1e-6)


def test_packaged_sky():
    path = mcs.data.sky_path()
    assert path.stat().st_size < 300_000
    lum = SKY.image @ np.array([0.2126, 0.7152, 0.0722])
    assert lum.max() / lum.min() > 1e4
    # The sun is up: the brightest texel is above the horizon.
    y, x = np.unravel_index(np.argmax(lum), lum.shape)
    assert SKY.uv_to_dir([(x + 0.5) / lum.shape[1], y / (lum.shape[0] - 1)])[1] > 0.3


def test_truncated_file_is_an_oserror(tmp_path):
    path = tmp_path / "sky.exr"
    mcs.io.write_exr(path, SKY.image)
    path.write_bytes(path.read_bytes()[:2000])
    with pytest.raises(OSError, match="sky.exr"):
        mcs.EnvMap.load(path)


def test_luminance_sampling_follows_the_radiance():
    """The lat-long default (sampling="luminance") draws directions in
    proportion to the bilinear luminance Y inside texels: the weights
    Y(L)/pdf of env-only samples of the sky stay within a few % of each
    other (the ratio s̄/sin θ of a texel row's mean sin θ), where the
    piecewise density's spread by ~40 %; both average ∫ Y dω."""
    luminance = np.array([0.2126, 0.7152, 0.0722])
    truth = integrate(SKY, lambda d: SKY.eval(d) @ luminance)
    u = mcs.uniform(200_000, 2, seed=5)
    spread = {}
    for sampling in ("luminance", "piecewise"):
        env = mcs.EnvMap(SKY.image, sampling=sampling)
        w = env.sample(u).weight @ luminance
        spread[sampling] = w.std() / w.mean()
        assert abs(w.mean() - truth) < 4 * w.std() / np.sqrt(len(w)) + 1e-9 * truth
    assert SKY.sampling == "luminance"
    assert spread["luminance"] < 0.03 and spread["piecewise"] > 0.2, spread
