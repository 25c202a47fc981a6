"""Chunked renders: ``mcs.render(..., first_sample=k)`` renders samples
``k .. k+spp-1`` of each pixel's sequence, and ``RenderResult.merge`` of
chunks covering ``0 .. S-1`` has the bits of one render of ``S`` spp (image
and both variances), for every sampler, integrator and chunking; chunks of
different renders, with gaps or overlaps, are refused."""

from __future__ import annotations

import copy
import pickle
import random

import numpy as np
import pytest

import mcsample as mcs
from mcsample.demo import demo_scene
from scenes import lit_room

SAMPLERS = ("independent", "stratified", "multijitter", "sobol", "ldsampler", "zsobol")
FIELDS = ("image", "variance", "luminance_variance")


@pytest.fixture(scope="module")
def demo():
    return mcs.Scene.from_mitsuba(demo_scene(40, 16))


@pytest.fixture(scope="module")
def room():
    return mcs.Scene.from_mitsuba(lit_room(width=24, height=16))


def assert_same_bits(a: mcs.RenderResult, b: mcs.RenderResult) -> None:
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype == np.float32 and x.shape == y.shape, name
        np.testing.assert_array_equal(x.view(np.uint32), y.view(np.uint32), err_msg=name)


def chunks(scene, cuts, **kw):
    total = cuts[-1]
    return [mcs.render(scene, b - a, first_sample=a, total_spp=total, progress=False, **kw)
            for a, b in zip(cuts[:-1], cuts[1:])]


@pytest.mark.parametrize("sampler", SAMPLERS)
@pytest.mark.parametrize("integrator", ["direct", "path"])
def test_merged_chunks_have_the_bits_of_one_render(demo, sampler, integrator):
    kw = dict(integrator=integrator, sampler=sampler, seed=11)
    one = mcs.render(demo, 16, progress=False, **kw)
    for cuts in ([0, 16], [0, 8, 16], [0, 1, 2, 7, 16], [0, 5, 6, 13, 16]):
        parts = chunks(demo, cuts, **kw)
        random.Random(len(cuts)).shuffle(parts)  # any order
        merged = mcs.RenderResult.merge(parts)
        assert_same_bits(merged, one)
        assert (merged.spp, merged.first_sample) == (16, 0)


@pytest.mark.parametrize("strategy", ["bsdf", "emitter", "mis"])
def test_area_lights_and_russian_roulette_chunk_exactly(room, strategy):
    kw = dict(integrator="path", strategy=strategy, seed=4, max_depth=-1, rr_depth=1)
    one = mcs.render(room, 12, progress=False, **kw)
    assert_same_bits(mcs.RenderResult.merge(chunks(room, [0, 3, 4, 12], **kw)), one)


def test_merges_merge_again_and_pickle(demo):
    """A progressive reference: merge what is done, render more, merge on;
    a chunk that went through pickle (as to a worker and back) merges the
    same."""
    kw = dict(integrator="path", seed=2, total_spp=24, progress=False)
    first = mcs.RenderResult.merge([mcs.render(demo, 8, first_sample=0, **kw),
                                    mcs.render(demo, 5, first_sample=8, **kw)])
    assert first.first_sample == 0 and first.spp == 13
    later = pickle.loads(pickle.dumps(mcs.render(demo, 11, first_sample=13, **kw)))
    both = mcs.RenderResult.merge([copy.deepcopy(first), later])
    assert_same_bits(both, mcs.render(demo, 24, integrator="path", seed=2, progress=False))
    # A merge that does not start at 0 is a chunk too.
    tail = mcs.RenderResult.merge([mcs.render(demo, 4, first_sample=13, **kw),
                                   mcs.render(demo, 7, first_sample=17, **kw)])
    assert (tail.first_sample, tail.spp) == (13, 11)
    assert_same_bits(mcs.RenderResult.merge([first, tail]), both)


def test_first_sample_zero_is_the_plain_render_and_chunks_differ(demo):
    one = mcs.render(demo, 8, seed=1, progress=False)
    assert one.chunk is None and one.first_sample == 0
    zero = mcs.render(demo, 8, seed=1, first_sample=0, progress=False)
    assert_same_bits(zero, one)
    assert zero.chunk is not None and zero.chunk.blocks == [(0, 8)]
    # Later samples are other samples: not the first ones again.
    later = mcs.render(demo, 8, seed=1, first_sample=8, progress=False)
    assert not np.array_equal(later.image, one.image)
    assert later.chunk.blocks == [(8, 8)]


def test_chunk_sums_are_what_the_image_is_made_of(demo):
    """The kept sums give the chunk's own mean and variance."""
    r = mcs.render(demo, 6, seed=3, first_sample=2, progress=False)
    assert r.chunk.blocks == [(2, 2), (4, 4)]
    sums = r.chunk.sums.reshape(*r.image.shape[:2], 2, 8).sum(axis=2)
    np.testing.assert_allclose(sums[..., :3] / 6, r.image, rtol=1e-6, atol=1e-7)
    var = (sums[..., 3:6] - sums[..., :3] ** 2 / 6) / 5 / 6
    np.testing.assert_allclose(var, r.variance, rtol=1e-4, atol=1e-9)


def test_bad_merges_are_refused(demo):
    kw = dict(progress=False, total_spp=8)
    a = mcs.render(demo, 4, first_sample=0, seed=1, **kw)
    b = mcs.render(demo, 4, first_sample=4, seed=1, **kw)
    with pytest.raises(ValueError, match="do not follow one another"):
        mcs.RenderResult.merge([a, mcs.render(demo, 2, first_sample=6, seed=1, **kw)])
    with pytest.raises(ValueError, match="do not follow one another"):
        mcs.RenderResult.merge([a, mcs.render(demo, 6, first_sample=2, seed=1, **kw)])
    with pytest.raises(ValueError, match="different renders"):
        mcs.RenderResult.merge([a, mcs.render(demo, 4, first_sample=4, seed=2, **kw)])
    # A sampler whose patterns span total_spp: 8 for one, 6 for the other.
    strat = dict(seed=1, sampler="stratified", progress=False)
    with pytest.raises(ValueError, match="different renders"):
        mcs.RenderResult.merge([mcs.render(demo, 4, first_sample=0, total_spp=8, **strat),
                                mcs.render(demo, 2, first_sample=4, **strat)])
    # The independent sampler's do not: a render continues with more samples.
    ind = dict(seed=1, progress=False)
    assert_same_bits(mcs.RenderResult.merge([mcs.render(demo, 4, first_sample=0, **ind),
                                             mcs.render(demo, 2, first_sample=4, **ind)]),
                     mcs.render(demo, 6, **ind))
    with pytest.raises(ValueError, match="different renders"):
        mcs.RenderResult.merge([a, mcs.render(demo, 4, first_sample=4, seed=1,
                                              strategy="bsdf", **kw)])
    with pytest.raises(ValueError, match="first_sample="):
        mcs.RenderResult.merge([a, mcs.render(demo, 4, seed=1, progress=False)])
    with pytest.raises(ValueError, match="empty"):
        mcs.RenderResult.merge([])
    assert mcs.RenderResult.merge([b, a]).spp == 8


def test_bad_chunk_arguments_are_refused(demo):
    with pytest.raises(ValueError, match="total_spp"):
        mcs.render(demo, 4, first_sample=6, total_spp=8, progress=False)
    with pytest.raises(ValueError, match="first_sample"):
        mcs.render(demo, 4, first_sample=-1, progress=False)
    with pytest.raises(ValueError, match="spp"):
        mcs.render(demo, 4, first_sample=0, total_spp=2**40, sampler="sobol", progress=False)
    with pytest.raises(TypeError):
        mcs.render(demo, 4, first_sample=1.5, progress=False)


# Estimators: chunks of evaluations, merged to the bits of one run.

PART = 16384  # evaluations per partial sum


@pytest.mark.parametrize("sampler", ["independent", "sobol", "stratified"])
@pytest.mark.parametrize("kind", ["irradiance", "reflected"])
def test_estimator_chunks_merge_to_one_run(sampler, kind):
    env = mcs.EnvMap()
    n = 3 * PART + 1000
    if kind == "irradiance":
        def run(**kw):
            return mcs.estimators.irradiance(env, [0.2, 1, 0.1], seed=5, sampler=sampler,
                                             strategy="mis", **kw)
    else:
        phong = mcs.Phong([0.2] * 3, [0.5] * 3, 30.0)

        def run(**kw):
            return mcs.estimators.reflected_radiance(env, phong, [0, 1, 0], [0.3, 0.9, 0],
                                                     seed=5, sampler=sampler, **kw)
    one = run(n=n)
    assert not one.mergeable and one.first_sample == 0
    for cuts in ([0, n], [0, PART, n], [0, PART, 3 * PART, n]):
        parts = [run(n=b - a, first_sample=a, total_n=n) for a, b in zip(cuts[:-1], cuts[1:])]
        merged = mcs.estimators.Estimate.merge(parts[::-1])
        assert merged.n == n and merged.mergeable and merged.first_sample == 0
        np.testing.assert_array_equal(merged.value, one.value)
        np.testing.assert_array_equal(merged.stderr, one.stderr)
    # Through pickle (as to a worker and back) and merged again.
    head = pickle.loads(pickle.dumps(run(n=2 * PART, first_sample=0, total_n=n)))
    tail = run(n=n - 2 * PART, first_sample=2 * PART, total_n=n)
    both = mcs.estimators.Estimate.merge([mcs.estimators.Estimate.merge([head]), tail])
    np.testing.assert_array_equal(both.value, one.value)


def test_bad_estimator_chunks_are_refused():
    env = mcs.EnvMap()
    run = lambda n, k, **kw: mcs.estimators.irradiance(env, [0, 1, 0], n, first_sample=k,  # noqa: E731
                                                       **kw)
    with pytest.raises(ValueError, match="multiple of 16384"):
        run(100, 10)
    with pytest.raises(ValueError, match="total_n"):
        run(PART, PART, total_n=PART)
    a, c = run(PART, 0), run(PART, 2 * PART)
    with pytest.raises(ValueError, match="do not follow one another"):
        mcs.estimators.Estimate.merge([a, c])
    with pytest.raises(ValueError, match="first_sample="):
        mcs.estimators.Estimate.merge([a, mcs.estimators.irradiance(env, [0, 1, 0], PART)])
    with pytest.raises(ValueError, match="one strategy"):
        mcs.estimators.Estimate.merge(
            [a, run(PART, PART, strategy="cosine")])
    with pytest.raises(ValueError, match="empty"):
        mcs.estimators.Estimate.merge([])
    with pytest.raises(ValueError, match="different runs"):
        mcs.estimators.Estimate.merge([a, run(PART, PART, seed=9)])
    with pytest.raises(ValueError, match="different runs"):
        mcs.estimators.Estimate.merge([a, run(PART, PART, sampler="sobol", total_n=2 * PART)])
    # Its settings travel with it.
    assert mcs.estimators.Estimate.merge([pickle.loads(pickle.dumps(a)), run(PART, PART)]).n == \
        2 * PART
