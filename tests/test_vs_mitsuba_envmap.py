"""EnvMap against Mitsuba 3's envmap emitter, on the packaged sky, a one-hot
map and a sky baked from Mitsuba's sunsky emitter: eval and uv for the same
directions, pdf in "mitsuba" mode (also with MIS compensation), Mitsuba's
samples against our pdf (chi-square), the same direction as Mitsuba's
for the same u in "mitsuba" mode, a two-sample test between the two
samplers, and Mitsuba's own weight = eval / pdf."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import mitsuba as mcs_mitsuba
from mcsample import stats

pytestmark = pytest.mark.mitsuba

ROTATION_AXIS = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])


@pytest.fixture(scope="module")
def maps(mi):
    """The three test maps, (H, W, 3) float32."""
    import drjit as dr

    one_hot = np.zeros((32, 64, 3), np.float32)
    one_hot[9, 20] = [50.0, 80.0, 20.0]
    # A real sky: Mitsuba's sunsky emitter baked at 4 x 4 points per texel.
    h, w, k = 64, 128, 4
    off = (np.arange(k) + 0.5) / k - 0.5
    u = (np.arange(w)[None, :, None, None] + 0.5 + off[None, None, :, None]) / w
    v = np.clip((np.arange(h)[:, None, None, None] + off[None, None, None, :]) / (h - 1), 0, 1)
    u, v = np.broadcast_arrays(u, v)
    theta, phi = np.pi * v.ravel(), 2 * np.pi * u.ravel()
    d = np.stack([np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)])
    sunsky = mi.load_dict({"type": "sunsky", "sun_direction": [0.5, 0.6, 0.3]})
    if mi.variant().startswith("scalar"):
        pytest.skip("baking a sky needs the vectorised (llvm) variant")
    si = dr.zeros(mi.SurfaceInteraction3f, d.shape[1])
    si.wi = mi.Vector3f(-d)
    baked = np.array(sunsky.eval(si)).T.reshape(h, w, k, k, 3).mean(axis=(2, 3))
    return {"sky": mcs.EnvMap().image, "one-hot": one_hot,
            "sunsky": np.ascontiguousarray(baked, dtype=np.float32)}


def _emitter(image, to_world=None, scale=1.0, compensate=False):
    import mitsuba as mi

    d = mcs_mitsuba.envmap_dict(mcs.EnvMap(image, scale=scale, compensate=compensate))
    if to_world is not None:
        d["to_world"] = to_world  # Mitsuba's own transform, as the user gave it
    return mi.load_dict(d)


def _directions(n=20000, seed=3):
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1)[:, None]


def _llvm(mi):
    if mi.variant().startswith("scalar"):
        pytest.skip("needs the llvm variant for vectorised batches")


def _float32_close(ours, theirs, what):
    """Equal to float32 precision: a direction in float32 moves the lookup by
    ~1e-7 of a turn, which across a steep texel gradient (the sun's rim) is
    up to a few 1e-4 relative (more where MIS compensation subtracts nearly
    equal numbers); the bulk agrees to ~1e-6."""
    rel = np.abs(ours - theirs) / np.maximum(np.abs(theirs), 1e-4 * np.abs(theirs).max())
    assert np.median(rel) < 2e-6, (what, np.median(rel))
    assert np.quantile(rel, 0.999) < 3e-4, (what, np.quantile(rel, 0.999))
    assert rel.max() < 3e-3, (what, rel.max())


@pytest.mark.parametrize("name", ["sky", "one-hot", "sunsky"])
@pytest.mark.parametrize("rotated", [False, True])
def test_eval_equals_mitsubas(mi, maps, name, rotated):
    _llvm(mi)
    to_world = mi.ScalarTransform4f().rotate(list(ROTATION_AXIS), 40) if rotated else None
    scale = 2.5 if rotated else 1.0
    image = maps[name]
    d = _directions()
    ours = mcs.EnvMap(image, to_world=to_world, scale=scale)
    theirs = mcs_mitsuba.emitter_eval(_emitter(image, to_world, scale), d)
    _float32_close(ours.eval(d), theirs, "eval")


@pytest.mark.parametrize("name", ["sky", "one-hot", "sunsky"])
@pytest.mark.parametrize("compensate", [False, True])
def test_pdf_in_mitsuba_mode_equals_mitsubas(mi, maps, name, compensate):
    _llvm(mi)
    to_world = mi.ScalarTransform4f().rotate(list(ROTATION_AXIS), 40)
    image = maps[name]
    ours = mcs.EnvMap(image, to_world=to_world, sampling="mitsuba", compensate=compensate)
    emitter = _emitter(image, to_world, compensate=compensate)
    d = _directions()
    # Directions where Mitsuba's density is positive, plus its own samples.
    u = mcs.uniform(20000, 2, seed=11)
    d = np.concatenate([d, mcs_mitsuba.emitter_sample(emitter, u)[0]])
    _float32_close(ours.pdf(d), mcs_mitsuba.emitter_pdf(emitter, d), "pdf")


def test_uv_of_mitsubas_samples(mi, maps):
    """dir_to_uv(d) is Mitsuba's uv of the sample in direction d."""
    _llvm(mi)
    emitter = _emitter(maps["sunsky"])
    d, _, _, uv = mcs_mitsuba.emitter_sample(emitter, mcs.uniform(20000, 2, seed=5))
    ours = mcs.EnvMap(maps["sunsky"]).dir_to_uv(d)
    diff = (ours - uv + 0.5) % 1.0 - 0.5  # Mitsuba's u runs past 1 by half a texel
    assert np.abs(diff).max() < 1e-5


@pytest.mark.parametrize("name", ["sky", "one-hot", "sunsky"])
def test_mitsubas_samples_follow_our_mitsuba_mode_pdf(mi, maps, name):
    _llvm(mi)
    emitter = _emitter(maps[name])
    ours = mcs.EnvMap(maps[name], sampling="mitsuba")
    result = stats.chi2_test(lambda u: mcs_mitsuba.emitter_sample(emitter, u).direction,
                             ours.pdf, "sphere", res=51, ires=8, integration="jittered",
                             test_count=3)
    assert result.passed, result.message


@pytest.mark.parametrize("name", ["sky", "one-hot", "sunsky"])
@pytest.mark.parametrize("sampling", ["luminance", "piecewise", "mitsuba"])
def test_our_samples_follow_our_pdf(mi, maps, name, sampling):
    env = mcs.EnvMap(maps[name], sampling=sampling)
    if sampling != "piecewise":
        # A density with kinks and the sun's peak across the cells: expected
        # counts by jittered (unbiased) integration.
        domain, res, ires, integration = "sphere", 51, 8, "jittered"
    else:
        domain = stats.EnvMapDomain(env)
        res, ires, integration = domain.cells, 4, "trapezoid"
    result = stats.chi2_test(lambda u: env.sample(u).direction, env.pdf, domain, res=res,
                             ires=ires, integration=integration, test_count=6)
    assert result.passed, result.message


@pytest.mark.parametrize("name", ["sky", "one-hot", "sunsky"])
def test_mitsuba_mode_maps_each_u_to_mitsubas_direction(mi, maps, name):
    """"mitsuba" sampling warps the square as Mitsuba's Hierarchical2D
    does: the same u gives the same direction (to float32 precision) but
    for the rare u that Mitsuba's float32 arithmetic sends across one of
    its choices' boundaries (measured: at most 0.007 %), so that a
    stratified sampler's points are spread over the map alike on both
    sides. (A marginal-then-conditional inversion of the same density
    gives another map: on the packaged sky 99.99 % of the directions
    differ.)"""
    _llvm(mi)
    emitter = _emitter(maps[name])
    u = mcs.uniform(100_000, 2, seed=8)
    theirs = mcs_mitsuba.emitter_sample(emitter, u)[0]
    ours = mcs.EnvMap(maps[name], sampling="mitsuba").sample(u).direction
    far = np.linalg.norm(ours - theirs, axis=1) > 1e-4
    print(name, far.mean())
    assert far.mean() < 1e-3, far.mean()


@pytest.mark.parametrize("name", ["sky", "one-hot", "sunsky"])
def test_two_sample_test_against_mitsubas_sampler(mi, maps, name):
    _llvm(mi)
    emitter = _emitter(maps[name])
    ours = mcs.EnvMap(maps[name], sampling="mitsuba")
    a = ours.sample(mcs.uniform(1_000_000, 2, seed=21)).direction
    b = mcs_mitsuba.emitter_sample(emitter, mcs.uniform(1_000_000, 2, seed=22))[0]
    result = stats.two_sample_test(a, b, "sphere")
    assert result.passed, result.message


@pytest.mark.parametrize("name", ["sky", "one-hot", "sunsky"])
def test_weights_are_eval_over_pdf(mi, maps, name):
    """Mitsuba's own check (its test02_sampling_weights), on both samplers."""
    _llvm(mi)
    emitter = _emitter(maps[name])
    d, pdf, weight, _ = mcs_mitsuba.emitter_sample(emitter, mcs.uniform(50000, 2, seed=4))
    ok = pdf > 0
    # Mitsuba looks its weight up at the sampled uv and eval at the float32
    # direction: they agree to float32 round-off across a texel gradient.
    np.testing.assert_allclose(weight[ok] * pdf[ok, None],
                               mcs_mitsuba.emitter_eval(emitter, d[ok]),
                               rtol=2e-3, atol=1e-6)
    for sampling in ["luminance", "piecewise", "mitsuba"]:
        ours = mcs.EnvMap(maps[name], sampling=sampling)
        s = ours.sample(mcs.uniform(50000, 2, seed=4))
        ok = s.pdf > 0
        np.testing.assert_allclose(s.weight[ok] * s.pdf[ok, None], ours.eval(s.direction[ok]),
                                   rtol=1e-6, atol=1e-9)


def test_piecewise_mode_is_unbiased_where_mitsuba_is_not(mi):
    """A map lit in its top row (and dimly at the horizon): Mitsuba's density
    is 0 near the pole (sin 0 on the pole's vertices, a black row below), so
    its envmap sampling misses that light; ours does not. (Lit only at the
    pole, Mitsuba's table is all zero and its pdf NaN.)"""
    _llvm(mi)
    image = np.zeros((16, 32, 3), np.float32)
    image[0] = 5.0
    image[8] = 0.01
    emitter = _emitter(image)
    d = np.array([[0.01, 0.9999, 0.0]])
    d /= np.linalg.norm(d)
    assert mcs_mitsuba.emitter_eval(emitter, d)[0, 0] > 0
    assert mcs_mitsuba.emitter_pdf(emitter, d)[0] == 0
    assert mcs.EnvMap(image).pdf(d)[0] > 0
