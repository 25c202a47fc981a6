"""The textbook estimators: irradiance by uniform, cosine, envmap and MIS
sampling, and reflected radiance from Phong surfaces by BSDF, envmap and MIS
sampling, each against quadrature over the map's texels; standard errors
that shrink as 1/sqrt(n); determinism."""

import functools

import numpy as np
import pytest

import mcsample as mcs
from mcsample import estimators

SKY = mcs.EnvMap()
SMOOTH = mcs.EnvMap(np.clip(SKY.image, 0, 2.0))  # the sky without its sun
NORMALS = {"up": [0, 1, 0], "tilted": [0.6, 0.5, 0.3], "toward the ground": [0.2, -0.9, 0.1]}


@pytest.mark.parametrize("strategy", ["uniform", "cosine", "emitter", "mis"])
@pytest.mark.parametrize("normal", list(NORMALS))
def test_irradiance_matches_quadrature(strategy, normal):
    env = SMOOTH if strategy in ("uniform", "cosine") else SKY
    truth = estimators.irradiance_reference(env, NORMALS[normal])
    e = estimators.irradiance(env, NORMALS[normal], 1_000_000, strategy=strategy, seed=3)
    assert e.n == 1_000_000 and e.value.shape == e.stderr.shape == (3,)
    assert np.all(np.abs(e.value - truth) < 4 * e.stderr + 1e-4 * truth), (e, truth)


def test_uniform_and_cosine_find_the_sun_too():
    """With the sun, hemisphere sampling is unbiased but noisy: 10^7 samples."""
    truth = estimators.irradiance_reference(SKY, NORMALS["tilted"])
    for strategy in ["uniform", "cosine"]:
        e = estimators.irradiance(SKY, NORMALS["tilted"], 10_000_000, strategy=strategy, seed=5)
        assert np.all(np.abs(e.value - truth) < 4 * e.stderr), (e, truth)


@pytest.mark.parametrize("strategy", ["uniform", "cosine", "emitter", "mis"])
def test_standard_error_shrinks_as_one_over_sqrt_n(strategy):
    small = estimators.irradiance(SMOOTH, NORMALS["tilted"], 10_000, strategy=strategy, seed=1)
    large = estimators.irradiance(SMOOTH, NORMALS["tilted"], 1_000_000, strategy=strategy, seed=2)
    ratio = small.stderr / large.stderr
    assert np.all((ratio > 8) & (ratio < 12.5)), ratio


def test_sampling_the_light_beats_the_hemisphere_under_a_sun():
    errs = {s: estimators.irradiance(SKY, NORMALS["tilted"], 100_000, strategy=s, seed=9).stderr[1]
            for s in ["uniform", "cosine", "emitter", "mis"]}
    assert errs["emitter"] < errs["cosine"] < errs["uniform"]
    assert errs["mis"] < errs["cosine"]


GLOSSY_NORMAL, GLOSSY_WI = [0.1, 1.0, -0.2], [0.6, 0.5, 0.6]


@functools.lru_cache(maxsize=None)
def reflected_truth(exponent):
    # The sun is ~2 texels wide and the lobe of n = 100 ~3 texels: refine.
    phong = mcs.Phong([0.3, 0.25, 0.2], [0.6, 0.6, 0.6], exponent)
    return estimators.reflected_radiance_reference(SKY, phong, GLOSSY_NORMAL, GLOSSY_WI, k=12)


@pytest.mark.parametrize("strategy", ["bsdf", "emitter", "mis"])
@pytest.mark.parametrize("exponent", [1.0, 10.0, 100.0])
@pytest.mark.parametrize("heuristic", ["balance", "power"])
def test_reflected_radiance_matches_quadrature(strategy, exponent, heuristic):
    phong = mcs.Phong([0.3, 0.25, 0.2], [0.6, 0.6, 0.6], exponent)
    truth = reflected_truth(exponent)
    e = estimators.reflected_radiance(SKY, phong, GLOSSY_NORMAL, GLOSSY_WI, 1_000_000, strategy=strategy,
                                      seed=4, heuristic=heuristic)
    assert np.all(np.abs(e.value - truth) < 4 * e.stderr + 2e-3 * truth), (e, truth)


def test_mis_wins_on_glossy_surfaces_under_the_sun():
    """Where each single strategy has a weak spot, MIS is close to the best."""
    normal, wi = [0.0, 1.0, 0.0], [0.6, 0.5, 0.6]
    for exponent in [1.0, 1000.0]:
        phong = mcs.Phong(0.2, 0.7, exponent)
        err = {s: estimators.reflected_radiance(SKY, phong, normal, wi, 100_000, strategy=s,
                                                seed=2).stderr[1]
               for s in ["bsdf", "emitter", "mis"]}
        assert err["mis"] < 1.5 * min(err["bsdf"], err["emitter"]), (exponent, err)


def test_estimates_do_not_depend_on_the_thread_count():
    results = []
    for threads in [1, 2, 3]:
        mcs.set_num_threads(threads)
        e = estimators.reflected_radiance(SKY, mcs.Phong(0.2, 0.5, 20), [0, 1, 0], [0, 1, 1],
                                          200_000, strategy="mis", seed=7)
        results.append((tuple(e.value), tuple(e.stderr)))
    assert results[0] == results[1] == results[2]


@pytest.mark.parametrize("call,fragment", [
    (lambda: estimators.irradiance(SKY, [0, 1, 0], 10, strategy="bsdf"), 'strategy = "bsdf"'),
    (lambda: estimators.reflected_radiance(SKY, mcs.Phong(0.2, 0.2, 2), [0, 1, 0], [0, 1, 0],
                                           10, strategy="cosine"), 'strategy = "cosine"'),
    (lambda: estimators.irradiance(SKY, [0, 0, 0], 10), "normal"),
    (lambda: estimators.irradiance(SKY, [0, 1, 0], 0), "n = 0"),
    (lambda: estimators.irradiance(SKY, [0, 1], 10), "normal must have shape (3,)"),
    (lambda: estimators.irradiance(SKY, [0, 1, 0], 10, heuristic="max"), 'heuristic = "max"'),
    (lambda: estimators.irradiance(SKY, [0, 1, 0], 10, seed=-1), "seed = -1"),
])
def test_bad_arguments(call, fragment):
    with pytest.raises(ValueError) as info:
        call()
    assert fragment in str(info.value)
