"""The numpy implementations that the benchmarks time beside mcsample compute
the same warps (so that their speeds compare like with like)."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample.bench import kernels as bench

CASES = [
    ("square_to_uniform_disk", bench._numpy_uniform_disk, ()),
    ("square_to_uniform_disk_concentric", bench._numpy_concentric_disk, ()),
    ("square_to_uniform_sphere", bench._numpy_uniform_sphere, ()),
    ("square_to_uniform_hemisphere", bench._numpy_uniform_hemisphere, ()),
    ("square_to_cosine_hemisphere", bench._numpy_cosine_hemisphere, ()),
    ("square_to_uniform_cone", bench._numpy_uniform_cone, (0.3,)),
    ("square_to_uniform_triangle", bench._numpy_uniform_triangle, ()),
    ("square_to_cosine_power_hemisphere", bench._numpy_cosine_power_hemisphere, (10.0,)),
]


@pytest.mark.parametrize("name, numpy_impl, args", CASES, ids=[c[0] for c in CASES])
def test_numpy_references_compute_the_same_warp(name, numpy_impl, args):
    u = mcs.uniform(10_000, 2, seed=11)
    # The edges and the centre of the square, where the formulas branch.
    u[:5] = [[0.0, 0.0], [1.0, 1.0], [0.5, 0.5], [0.0, 1.0], [0.25, 0.75]]
    ours = getattr(mcs.warp, name)(u, *args)
    np.testing.assert_allclose(numpy_impl(u, *args), ours, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("suite", ["rng", "warps", "distr", "phong", "envmap", "qmc"])
def test_kernel_suites_run(suite):
    """Each kernel suite of ``python -m mcsample bench`` runs (here at a tiny
    size, without Mitsuba) and times every case it lists."""
    from mcsample.bench import SUITES

    timings = SUITES[suite](2000, 1, None)
    assert timings and all(t.seconds > 0 for t in timings)
