"""mcsample.qmc: scipy's plain points bit for bit, the scrambles' nets and
uniformity over seeds, the engine interface, and warps fed by the points."""

import numpy as np
import pytest
from scipy import stats as scipy_stats
from scipy.stats import qmc as scipy_qmc

import mcsample as mcs
from mcsample import qmc, stats, warp

SEQUENCES = [
    lambda d, seed: qmc.Sobol(d, scramble=True, seed=seed),
    lambda d, seed: qmc.Sobol(d, scramble="lms", seed=seed),
    lambda d, seed: qmc.Halton(d, scramble=True, seed=seed),
]
PATTERNS = [
    lambda d, seed: qmc.LatinHypercube(d, seed=seed),
    lambda d, seed: qmc.Stratified(d, seed=seed),
    lambda d, seed: qmc.MultiJitter(d, seed=seed),
]
SCRAMBLED = SEQUENCES + PATTERNS
SCRAMBLED_IDS = ["sobol-owen", "sobol-lms", "halton", "lhs", "stratified", "multijitter"]


def test_plain_sobol_is_scipys_for_every_dimension():
    """All 21201 dimensions (so every d, a point's first d coordinates),
    the first 2**10 points; then the points at 2**k - 1 and 2**k for every
    k < 30, which read column k of each generator matrix, against scipy's
    matrices (the Gray-code step from 2**k - 1 to 2**k adds column k)."""
    d = qmc.Sobol.MAXDIM
    ours = qmc.Sobol(d, scramble=False).random(2**10)
    theirs = scipy_qmc.Sobol(d, scramble=False).random(2**10)
    assert np.array_equal(ours, theirs)
    sv = getattr(scipy_qmc.Sobol(d, scramble=False, bits=30), "_sv", None)
    if sv is None:
        pytest.skip("scipy's Sobol no longer exposes its matrices")
    engine = qmc.Sobol(d, scramble=False)
    for k in range(10, 30):
        before, at = engine.reset().fast_forward(2**k - 1).random(2)
        # x(2**k) = x(2**k - 1) xor column k, in units of 2**-30.
        step = (np.round(before * 2**30).astype(np.int64)
                ^ np.round(at * 2**30).astype(np.int64))
        assert np.array_equal(step, sv[:, k].astype(np.int64)), k


@pytest.mark.parametrize("d", [1, 2, 3, 8, 21])
def test_plain_sobol_is_scipys_up_to_2_to_the_20(d):
    assert np.array_equal(qmc.Sobol(d, scramble=False).random(2**20),
                          scipy_qmc.Sobol(d, scramble=False).random(2**20))


def test_plain_sobol_continues_as_scipys():
    ours, theirs = qmc.Sobol(5, scramble=False), scipy_qmc.Sobol(5, scramble=False)
    for n in [1, 7, 8, 100, 1000]:
        assert np.array_equal(ours.random(n), theirs.random(n))
    ours.fast_forward(12345)
    theirs.fast_forward(12345)
    assert np.array_equal(ours.random(64), theirs.random(64))


@pytest.mark.parametrize("d, n", [(1000, 2**12), (8, 2**20)])
def test_plain_halton_is_scipys(d, n):
    assert np.array_equal(qmc.Halton(d, scramble=False).random(n),
                          scipy_qmc.Halton(d, scramble=False).random(n))


def test_plain_halton_continues_as_scipys():
    # Near the last index, every digit summed as scipy's van der Corput loop
    # sums them (written out here: scipy's fast_forward that far allocates
    # 2**53 values).
    def van_der_corput(i, base):
        total, scale = 0.0, 1.0 / base
        while i > 0:
            total += (i % base) * scale
            scale /= base
            i //= base
        return total

    far = 2**53 - 5
    points = qmc.Halton(8, scramble=False).fast_forward(far).random(4)
    bases = [2, 3, 5, 7, 11, 13, 17, 19]
    assert points.tolist() == [[van_der_corput(far + k, b) for b in bases] for k in range(4)]
    ours, theirs = qmc.Halton(4, scramble=False), scipy_qmc.Halton(4, scramble=False)
    ours.random(1000)
    theirs.random(1000)
    assert np.array_equal(ours.random(500), theirs.random(500))


@pytest.mark.parametrize("kind", ["owen", "lms", "plain"])
def test_scrambled_sobol_keeps_the_net_of_its_first_two_dimensions(kind):
    """Every prefix of 2**m points (m <= 14) has one point in each
    elementary box [a 2**-k, (a+1) 2**-k) x [b 2**-(m-k), ...)."""
    scramble = {"owen": True, "lms": "lms", "plain": False}[kind]
    x = qmc.Sobol(2, scramble=scramble, seed=5).random(2**14)
    bits = (x * 2**32).astype(np.uint64)
    for m in range(15):
        for k in range(m + 1):
            cells = ((bits[: 2**m, 0] >> np.uint64(32 - k)) << np.uint64(m - k)) | (
                bits[: 2**m, 1] >> np.uint64(32 - (m - k)))
            assert len(np.unique(cells)) == 2**m, (m, k)


@pytest.mark.parametrize("make", SCRAMBLED, ids=SCRAMBLED_IDS)
def test_each_scrambled_point_is_uniform_over_seeds(make):
    """Points 0, 1, 6 and 1000 over 4000 seeds: each coordinate passes a
    Kolmogorov-Smirnov test against U[0, 1) (Šidák over the 12 tests at
    1e-3), and two coordinates of one point are uncorrelated."""
    seeds = range(4000)
    picks = [0, 1, 6, 1000]
    values = np.array([make(3, s).fast_forward(0).random(1001)[picks] for s in seeds])
    p = [scipy_stats.kstest(values[:, i, j], "uniform").pvalue
         for i in range(len(picks)) for j in range(3)]
    assert min(p) > 1 - (1 - 1e-3) ** (1 / len(p)), p
    r = np.corrcoef(values[:, 3, 0], values[:, 3, 1])[0, 1]
    assert abs(r) < 5 / np.sqrt(len(seeds))


@pytest.mark.parametrize("make", SCRAMBLED, ids=SCRAMBLED_IDS)
def test_same_seed_same_points_other_seed_other_points(make):
    a, b, c = make(4, 1).random(256), make(4, 1).random(256), make(4, 2).random(256)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    gen = np.random.default_rng(9)
    assert np.array_equal(make(4, np.random.default_rng(9)).random(8), make(4, gen).random(8))


@pytest.mark.parametrize("make", SCRAMBLED + [lambda d, s: qmc.Sobol(d, scramble=False)],
                         ids=SCRAMBLED_IDS + ["sobol-plain"])
def test_points_do_not_depend_on_the_thread_count(make):
    before = mcs.get_num_threads()
    try:
        mcs.set_num_threads(1)
        one = make(6, 3).random(200_000)
        later_one = make(6, 3).fast_forward(123_457).random(100_000)
        mcs.set_num_threads(4)
        four = make(6, 3).random(200_000)
        later_four = make(6, 3).fast_forward(123_457).random(100_000)
    finally:
        mcs.set_num_threads(before)
    assert np.array_equal(one, four)
    assert np.array_equal(later_one, later_four)


@pytest.mark.parametrize("make", SCRAMBLED, ids=SCRAMBLED_IDS)
def test_engine_interface(make):
    e = make(3, 0)
    assert isinstance(e, scipy_qmc.QMCEngine) and e.d == 3
    first = e.random(10)
    assert first.shape == (10, 3) and first.dtype == np.float64
    assert ((first >= 0) & (first < 1)).all()
    assert e.num_generated == 10
    assert not np.array_equal(e.random(10), first)
    assert np.array_equal(e.reset().random(10), first)
    if make in SEQUENCES:
        # A sequence continues: skipping 4 points gives the rest.
        assert np.array_equal(e.reset().fast_forward(4).random(6), first[4:])
    f32 = e.reset().random(10, dtype=np.float32)
    assert f32.dtype == np.float32 and np.allclose(f32, first, atol=2**-23)
    assert ((f32 >= 0) & (f32 < 1)).all()
    # scipy's helpers take the engine.
    ints = e.reset().integers([0, 0, 0], u_bounds=[4, 5, 6], n=100)
    assert ints.shape == (100, 3) and (ints >= 0).all() and (ints < [4, 5, 6]).all()
    assert 0 < scipy_qmc.discrepancy(e.reset().random(256)) < 0.01


def test_scipy_interface_of_random_base2():
    e = qmc.Sobol(2, seed=0)
    assert e.random_base2(3).shape == (8, 2)
    assert e.random_base2(3).shape == (8, 2)  # 16 drawn: a power of two
    with pytest.raises(ValueError, match="power of 2"):
        e.random_base2(3)  # 16 + 8
    with pytest.raises(ValueError, match="m = -1"):
        e.random_base2(-1)


@pytest.mark.parametrize("n", [64, 100, 37])
def test_patterns_are_stratified(n):
    """LHS: one point per interval of 1/n in each dimension; Stratified: one
    per stratum of the r x r grid when n = r**2 (else distinct strata);
    MultiJitter: one per interval along y, and along x when n = m k."""
    def intervals(column, count):
        return len(np.unique((column * count).astype(int))) == len(column)

    lhs = qmc.LatinHypercube(5, seed=1).random(n)
    assert all(intervals(lhs[:, j], n) for j in range(5))
    centred = qmc.LatinHypercube(2, scramble=False, seed=1).random(n)
    assert np.allclose((centred * n) % 1, 0.5)
    r = int(np.ceil(np.sqrt(n)))
    strat = qmc.Stratified(3, seed=1).random(n)
    cells = (strat[:, 0] * r).astype(int) * r + (strat[:, 1] * r).astype(int)
    assert len(np.unique(cells)) == n
    assert intervals(strat[:, 2], n)
    mj = qmc.MultiJitter(2, seed=1).random(n)
    assert intervals(mj[:, 1], n)
    assert intervals(mj[:, 0], n) == (n != 37)


def test_bad_input():
    with pytest.raises(ValueError, match="d = 0"):
        qmc.Sobol(0)
    with pytest.raises(ValueError, match="d = 21202"):
        qmc.Sobol(21202)
    with pytest.raises(ValueError, match="d = 0"):
        qmc.Halton(0)
    with pytest.raises(ValueError, match="scramble"):
        qmc.Sobol(2, scramble="owen")
    with pytest.raises(ValueError, match="scramble"):
        qmc.Halton(2, scramble="lms")
    with pytest.raises(ValueError, match="scramble"):
        qmc.LatinHypercube(2, scramble="lms")
    with pytest.raises(ValueError, match="d = 0"):
        qmc.MultiJitter(0)
    with pytest.raises(ValueError, match="n = 1073741825"):
        qmc.Stratified(1).random(2**30 + 1)
    # Refused before anything is allocated.
    with pytest.raises(ValueError, match="below index 9007199254740992"):
        qmc.Halton(1, scramble=False).random(2**53 + 1)
    with pytest.raises(ValueError, match="n·d"):
        qmc.Sobol(21201).random(2**32)
    with pytest.raises(ValueError, match="m = 33"):
        qmc.Sobol(1).random_base2(33)
    with pytest.raises(ValueError, match="scrambled Halton sequence in 5000 dimensions"):
        qmc.Halton(5000)
    assert qmc.Halton(5000, scramble=False).random(2).shape == (2, 5000)
    assert qmc.Sobol(2, scramble=np.False_).random(2)[0].tolist() == [0.0, 0.0]
    with pytest.raises(ValueError, match="n = -3"):
        qmc.Sobol(2).fast_forward(-3)
    with pytest.raises(ValueError, match="n = -1"):
        qmc.Sobol(2).random(-1)
    with pytest.raises(TypeError, match="n must be an integer"):
        qmc.Sobol(2).random(2.5)
    with pytest.raises(ValueError, match="seed"):
        qmc.Sobol(2, seed=-1)
    with pytest.raises(TypeError, match="dtype"):
        qmc.Sobol(2).random(2, dtype=np.int32)
    # No wrap-around past the sequence's last index.
    e = qmc.Sobol(1, scramble=False).fast_forward(2**32 - 1)
    assert e.random(1).shape == (1, 1)
    with pytest.raises(ValueError, match="below index 4294967296"):
        e.random(1)


@pytest.mark.parametrize("make", SCRAMBLED, ids=SCRAMBLED_IDS)
def test_warps_fed_by_the_points_pass_chi_square(make):
    """A scrambled net is uniform: the cosine-hemisphere and the Phong-lobe
    warps fed by it keep their densities (and each test still rejects the
    lobe of a wrong exponent fed by the same points)."""
    def lobe(exponent):
        engine = make(2, 4)
        return lambda u: warp.square_to_cosine_power_hemisphere(engine.random(len(u)), exponent)

    engine = make(2, 3)
    ok = stats.chi2_test(lambda u: warp.square_to_cosine_hemisphere(engine.random(len(u))),
                         warp.square_to_cosine_hemisphere_pdf, "hemisphere", n=2**18,
                         res=(32, 64))
    assert ok.passed, ok.message
    good = stats.chi2_test(lobe(8.0),
                           lambda d: warp.square_to_cosine_power_hemisphere_pdf(d, 8.0),
                           "hemisphere", n=2**18, res=(32, 64))
    assert good.passed, good.message
    wrong = stats.chi2_test(lobe(8.4),
                            lambda d: warp.square_to_cosine_power_hemisphere_pdf(d, 8.0),
                            "hemisphere", n=2**18, res=(32, 64))
    assert not wrong.passed
