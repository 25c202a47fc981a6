"""The standard normal, Beckmann, von Mises-Fisher, rough-fibre, spherical
lune, tangent-direction and bilinear warps of ``mi.warp``: each sampler
against its own density (chi-square), inverse∘sample = identity, float32
against float64, against Mitsuba 3 on the same numbers, and bad
parameters."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats, warp

WI = np.array([0.3, 0.4, 0.866]) / np.linalg.norm([0.3, 0.4, 0.866])
X, Z = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
N1, N2 = np.array([0.0, 0.6, 0.8]), np.array([0.8, 0.6, 0.0])
CORNERS = (0.2, 1.5, 0.8, 1.5)


def _first(pair_fn):
    """The points of a sampler returning (points, pdf)."""
    return lambda u: pair_fn(u)[0]


# (name, sampler, density, domain, uniform numbers per sample)
CHI2 = [
    ("std_normal", warp.square_to_std_normal, warp.square_to_std_normal_pdf,
     ((-6.0, 6.0), (-6.0, 6.0)), 2),
    ("beckmann(0.1)", lambda u: warp.square_to_beckmann(u, 0.1),
     lambda d: warp.square_to_beckmann_pdf(d, 0.1), stats.HemisphereDomain(3.0), 2),
    ("beckmann(0.6)", lambda u: warp.square_to_beckmann(u, 0.6),
     lambda d: warp.square_to_beckmann_pdf(d, 0.6), "hemisphere", 2),
    ("beckmann(3)", lambda u: warp.square_to_beckmann(u, 3.0),
     lambda d: warp.square_to_beckmann_pdf(d, 3.0), "hemisphere", 2),
    ("vmf(0)", lambda u: warp.square_to_von_mises_fisher(u, 0.0),
     lambda d: warp.square_to_von_mises_fisher_pdf(d, 0.0), "sphere", 2),
    ("vmf(2)", lambda u: warp.square_to_von_mises_fisher(u, 2.0),
     lambda d: warp.square_to_von_mises_fisher_pdf(d, 2.0), "sphere", 2),
    ("vmf(300)", lambda u: warp.square_to_von_mises_fisher(u, 300.0),
     lambda d: warp.square_to_von_mises_fisher_pdf(d, 300.0), stats.SphericalDomain(4.0), 2),
    ("rough_fiber(1)", lambda u: warp.square_to_rough_fiber(u, WI, Z, 1.0),
     lambda d: warp.square_to_rough_fiber_pdf(d, WI, Z, 1.0), "sphere", 3),
    ("rough_fiber(30)", lambda u: warp.square_to_rough_fiber(u, WI, Z, 30.0),
     lambda d: warp.square_to_rough_fiber_pdf(d, WI, Z, 30.0), "sphere", 3),
    # Light at right angles to the fibre: the lobe lies where
    # c = kappa cos_i cos_o is near kappa, in I0's series (c = 20) and
    # asymptotic (c = 80) branches.
    ("rough_fiber(20) across", lambda u: warp.square_to_rough_fiber(u, X, Z, 20.0),
     lambda d: warp.square_to_rough_fiber_pdf(d, X, Z, 20.0), "sphere", 3),
    ("rough_fiber(80) across", lambda u: warp.square_to_rough_fiber(u, X, Z, 80.0),
     lambda d: warp.square_to_rough_fiber_pdf(d, X, Z, 80.0), "sphere", 3),
    ("spherical_lune", lambda u: warp.square_to_uniform_spherical_lune(u, N1, N2),
     lambda d: warp.square_to_uniform_spherical_lune_pdf(d, N1, N2), "sphere", 2),
    ("bilinear", _first(lambda u: warp.square_to_bilinear(*CORNERS, u)),
     lambda p: warp.square_to_bilinear_pdf(*CORNERS, p), "square", 2),
    ("bilinear(0, 0, 0, 1)", _first(lambda u: warp.square_to_bilinear(0, 0, 0, 1, u)),
     lambda p: warp.square_to_bilinear_pdf(0, 0, 0, 1, p), "square", 2),
]


@pytest.mark.parametrize("name,sample,pdf,domain,dim", CHI2, ids=[c[0] for c in CHI2])
def test_chi2_against_own_density(name, sample, pdf, domain, dim):
    result = stats.chi2_test(sample, pdf, domain, n=1_000_000, sample_dim=dim, seed=11,
                             test_count=len(CHI2) + 1)
    assert result.passed, result.message


def test_tangent_directions_are_uniform_in_angle():
    n = np.array([0.2, -0.5, 0.84]) / np.linalg.norm([0.2, -0.5, 0.84])
    # An angle measured in a frame of our own, not the warp's.
    a = np.cross(n, [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(n, a)

    def angle(u):
        d = warp.interval_to_tangent_direction(n, u[:, 0])
        assert np.allclose(d @ n, 0, atol=1e-12) and np.allclose(np.linalg.norm(d, axis=1), 1)
        return np.arctan2(d @ b, d @ a)

    result = stats.chi2_test(angle, lambda t: np.full(len(t), 1 / (2 * np.pi)), (-np.pi, np.pi),
                             n=1_000_000, seed=11, test_count=len(CHI2) + 1)
    assert result.passed, result.message


def test_a_wrong_concentration_is_rejected():
    """Power: the chi-square test tells kappa = 30 from 31 in the rough
    fibre, and alpha 0.6 from 0.62 in Beckmann's lobe."""
    fibre = stats.chi2_test(lambda u: warp.square_to_rough_fiber(u, WI, Z, 30.0),
                            lambda d: warp.square_to_rough_fiber_pdf(d, WI, Z, 31.0),
                            "sphere", n=1_000_000, sample_dim=3, seed=11)
    assert not fibre.passed
    beckmann = stats.chi2_test(lambda u: warp.square_to_beckmann(u, 0.6),
                               lambda d: warp.square_to_beckmann_pdf(d, 0.62),
                               "hemisphere", n=1_000_000, seed=11)
    assert not beckmann.passed


U = mcs.uniform(20_000, 2, seed=4)
U3 = mcs.uniform(20_000, 3, seed=4)

# (name, sample, inverse) for the warps with an inverse.
INVERSES = [
    ("beckmann(0.05)", lambda u: warp.square_to_beckmann(u, 0.05),
     lambda d: warp.beckmann_to_square(d, 0.05)),
    ("beckmann(2)", lambda u: warp.square_to_beckmann(u, 2.0),
     lambda d: warp.beckmann_to_square(d, 2.0)),
    ("vmf(0)", lambda u: warp.square_to_von_mises_fisher(u, 0.0),
     lambda d: warp.von_mises_fisher_to_square(d, 0.0)),
    ("vmf(1e-9)", lambda u: warp.square_to_von_mises_fisher(u, 1e-9),
     lambda d: warp.von_mises_fisher_to_square(d, 1e-9)),
    ("vmf(7)", lambda u: warp.square_to_von_mises_fisher(u, 7.0),
     lambda d: warp.von_mises_fisher_to_square(d, 7.0)),
    ("spherical_lune", lambda u: warp.square_to_uniform_spherical_lune(u, N1, N2),
     lambda d: warp.uniform_spherical_lune_to_square(d, N1, N2)),
    ("bilinear", _first(lambda u: warp.square_to_bilinear(*CORNERS, u)),
     _first(lambda p: warp.bilinear_to_square(*CORNERS, p))),
]


@pytest.mark.parametrize("name,sample,inverse", INVERSES, ids=[c[0] for c in INVERSES])
def test_inverse_undoes_the_warp(name, sample, inverse):
    # Away from where the inverse is ill-conditioned (the poles' and the
    # seam's azimuth, the horizon of a tight lobe).
    u = U[(np.abs(U - 0.5) < 0.49).all(axis=1)]
    assert np.allclose(inverse(sample(u)), u, atol=1e-7, rtol=0)


def test_tangent_direction_round_trip():
    n = np.array([0.2, -0.5, 0.84])
    u = U[:, 0]
    back = warp.tangent_direction_to_interval(n, warp.interval_to_tangent_direction(n, u))
    assert np.allclose(back, u, atol=1e-12, rtol=0)


def test_float32_keeps_float64_precision():
    """float32 points are the float64 ones to float32 precision (4e-6): the
    formulas avoid the cancellations Mitsuba's have near the pole and the
    horizon. (Near the south pole a wide vMF lobe loses precision as the
    uniform sphere's z = 1 - 2u does, in Mitsuba too.)"""
    u32 = U.astype(np.float32)
    for sample in (lambda u: warp.square_to_beckmann(u, 0.05),
                   lambda u: warp.square_to_beckmann(u, 0.5),
                   lambda u: warp.square_to_von_mises_fisher(u, 40.0),
                   warp.square_to_std_normal):
        d32, d64 = sample(u32), sample(u32.astype(np.float64))
        assert d32.dtype == np.float32
        assert np.allclose(d32, d64, atol=4e-6, rtol=4e-6), np.abs(d32 - d64).max()


def test_edges_are_finite():
    corners = np.array([[0, 0], [1, 1], [0, 1], [1, 0], [0.5, 0.5]], dtype=np.float64)
    for f32 in (False, True):
        u = corners.astype(np.float32) if f32 else corners
        outputs = [
            warp.square_to_std_normal(u),
            warp.square_to_beckmann(u, 0.01), warp.square_to_beckmann(u, 1e6),
            warp.square_to_von_mises_fisher(u, 0.0), warp.square_to_von_mises_fisher(u, 1e4),
            warp.square_to_uniform_spherical_lune(u, N1, N2),
            warp.square_to_bilinear(0, 0, 0, 1, u)[0],
        ]
        for out in outputs:
            assert np.isfinite(out).all(), out
    d = warp.square_to_von_mises_fisher(corners, 1e4)
    assert np.allclose(np.linalg.norm(d, axis=1), 1)
    assert warp.square_to_von_mises_fisher([0.0, 1.0], 1e4)[2] == -1
    assert np.isfinite(warp.square_to_beckmann_pdf([[1, 0, 0], [0, 0, 1], [0.6, 0, -0.8]], 0.3)).all()
    assert warp.square_to_beckmann_pdf([0.6, 0, -0.8], 0.3) == 0
    assert warp.square_to_uniform_spherical_lune_pdf([0, 1.0, 0], N1, N2) == 0
    assert warp.square_to_bilinear_pdf(*CORNERS, [1.5, 0.5]) == 0


def test_bilinear_density_is_normalised():
    """Corners at any scale give the same points and a density of mean 1:
    the interpolant divided by the corners' mean."""
    p1, pdf1 = warp.square_to_bilinear(1, 2, 3, 4, U)
    p2, pdf2 = warp.square_to_bilinear(10, 20, 30, 40, U)
    assert np.array_equal(p1, p2) and np.array_equal(pdf1, pdf2)
    assert np.allclose(warp.square_to_bilinear_pdf(1, 2, 3, 4, [[0, 0], [1, 1]]), [0.4, 1.6])
    assert np.allclose(pdf1, warp.square_to_bilinear_pdf(1, 2, 3, 4, p1))
    # Mean of the density over uniform points of the square: 1.
    assert abs(warp.square_to_bilinear_pdf(1, 2, 3, 4, U).mean() - 1) < 0.01


def test_rough_fiber_density_integrates_to_one():
    """Unbiased: the mean of pdf/(1/4pi) over uniform directions is 1, for
    the series (c <= 30) and the asymptotic (c > 30) branches of I0."""
    d = warp.square_to_uniform_sphere(mcs.uniform(2_000_000, 2, seed=9))
    for kappa, tangent in [(0.0, Z), (5.0, Z), (25.0, [1.0, 0, 0]), (200.0, [0.6, 0, 0.8])]:
        p = warp.square_to_rough_fiber_pdf(d, WI, tangent, kappa) * 4 * np.pi
        stderr = p.std() / np.sqrt(len(p))
        assert abs(p.mean() - 1) < 5 * stderr + 1e-3, (kappa, p.mean(), stderr)


def test_bad_parameters_name_themselves():
    u = [0.5, 0.5]
    for call, match in [
        (lambda: warp.square_to_beckmann(u, 0.0), "alpha = 0"),
        (lambda: warp.square_to_beckmann_pdf([0, 0, 1], -1.0), "alpha = -1"),
        (lambda: warp.beckmann_to_square([0, 0, 1], float("inf")), "alpha = inf"),
        (lambda: warp.square_to_von_mises_fisher(u, -0.5), "kappa = -0.5"),
        (lambda: warp.von_mises_fisher_to_square([0, 0, 1], float("nan")), "kappa = NaN"),
        (lambda: warp.square_to_rough_fiber([0.5] * 3, WI, Z, -1.0), "kappa = -1"),
        (lambda: warp.square_to_rough_fiber([0.5] * 3, [0, 0, 0], Z, 1.0), "wi = "),
        (lambda: warp.square_to_rough_fiber_pdf([0, 0, 1], WI, [0, float("nan"), 0], 1.0),
         "tangent = "),
        (lambda: warp.square_to_uniform_spherical_lune(u, N1, -N1), "parallel nor opposite"),
        (lambda: warp.square_to_uniform_spherical_lune(u, N1, 2 * N1), "parallel nor opposite"),
        (lambda: warp.square_to_uniform_spherical_lune_pdf([0, 0, 1], [0, 0, 0], N2), "n1 = "),
        (lambda: warp.interval_to_tangent_direction([0, 0, 0], 0.5), "n = "),
        (lambda: warp.square_to_bilinear(-1, 1, 1, 1, u), "v00 = -1"),
        (lambda: warp.square_to_bilinear_pdf(1, 1, float("nan"), 1, u), "v01 = NaN"),
        (lambda: warp.bilinear_to_square(0, 0, 0, 0, u), "must not all be 0"),
        (lambda: warp.square_to_bilinear(1, 1, 1, 1, [0.5, 1.5]), "sample"),
        (lambda: warp.square_to_beckmann([0.5, 1.5], 0.3), "sample"),
    ]:
        with pytest.raises(ValueError, match=match):
            call()
    with pytest.raises(ValueError, match="n1"):
        warp.square_to_uniform_spherical_lune(u, [0, 1], N2)
    u32 = np.float32(u)
    with pytest.raises(ValueError, match=r"alpha\^2 must be a positive finite"):
        warp.square_to_beckmann(u32, 1e20)
    with pytest.raises(ValueError, match="kappa = 10+: must be finite in the input's"):
        warp.square_to_von_mises_fisher(u32, 1e39)
    # Nearly parallel normals: a thin lune, finite density.
    thin = warp.square_to_uniform_spherical_lune_pdf([0, 0, 1.0], [1, 0, 0], [1, 1e-9, 0])
    assert np.isfinite(thin) and thin > 1e7


# ---------------------------------------------------------------- Mitsuba 3


def _mi_call(mi, fn, kinds, *args):
    """Calls ``fn`` of mi.warp on the columns of each array argument (as the
    Mitsuba type named in ``kinds``: "f", "p2", "p3", "v3", "n3"; "s" a
    scalar as a Float), with the other arguments as they are → float64 ndarray (rows, values)."""
    def wrap(kind, value, row=None):
        if kind is None:
            return value
        if kind == "s":  # a scalar as the variant's Float
            return mi.Float(float(value))
        cls = {"f": mi.Float, "p2": mi.Point2f, "p3": mi.Point3f, "v3": mi.Vector3f,
               "n3": mi.Normal3f}[kind]
        v = np.asarray(value, dtype=np.float32)
        if v.ndim == 2 or (kind == "f" and v.ndim == 1):  # one value or vector a row
            v = v[row] if row is not None else v.T
        if kind == "f":
            return mi.Float(v) if v.ndim else float(v)
        return cls(*v) if v.ndim == 2 else cls(*(float(c) for c in v))

    batch = next(len(a) for a in args if np.ndim(a) == 2 or (np.ndim(a) == 1 and len(a) > 3))
    if mi.variant().startswith("scalar"):
        rows = []
        for i in range(batch):
            wrapped = [wrap(k, a, i) for k, a in zip(kinds, args)]
            rows.append(np.array(fn(*wrapped), dtype=np.float64).reshape(-1))
        return np.array(rows)
    out = fn(*(wrap(k, a) for k, a in zip(kinds, args)))
    arr = np.array(out, dtype=np.float64)
    if arr.ndim == 0 or arr.size == 1:
        return np.full((batch, 1), arr.reshape(-1)[0])
    return arr.reshape(batch, 1) if arr.ndim == 1 else arr.T


@pytest.fixture(scope="module")
def u_mi(mi):
    n = 64 if mi.variant().startswith("scalar") else 20_000
    u = mcs.uniform(n, 3, seed=3, dtype=np.float32).astype(np.float64)
    return np.clip(u, 1e-3, 1 - 1e-3)  # away from the azimuth seam of the inverses


def _agree(ours, theirs, atol, rtol=1e-5):
    ours = np.asarray(ours, dtype=np.float64).reshape(theirs.shape)
    assert np.allclose(ours, theirs, atol=atol, rtol=rtol), np.abs(ours - theirs).max()


@pytest.mark.mitsuba
def test_std_normal_and_bilinear_agree_with_mitsuba(mi, u_mi):
    u = u_mi[:, :2]
    p = warp.square_to_std_normal(u)
    _agree(p, _mi_call(mi, mi.warp.square_to_std_normal, ["p2"], u), 2e-5)
    _agree(warp.square_to_std_normal_pdf(p), _mi_call(mi, mi.warp.square_to_std_normal_pdf,
                                                      ["p2"], p), 1e-7)
    corners = tuple(np.array(CORNERS) / np.mean(CORNERS))  # mean 1: Mitsuba's density
    kinds = ["s"] * 4 + ["p2"]
    q, pdf = warp.square_to_bilinear(*corners, u)
    if mi.variant().startswith("scalar"):
        theirs = [mi.warp.square_to_bilinear(*corners, mi.Point2f(*r)) for r in u]
        their_q = np.array([np.array(a) for a, _ in theirs])
        their_pdf = np.array([b for _, b in theirs])
        back = [mi.warp.bilinear_to_square(*corners, mi.Point2f(*r)) for r in q]
        their_back = np.array([np.array(a) for a, _ in back])
    else:
        corners = tuple(mi.Float(c) for c in corners)
        a, b = mi.warp.square_to_bilinear(*corners, mi.Point2f(*u.T.astype(np.float32)))
        their_q, their_pdf = np.array(a).T, np.array(b)
        c, _ = mi.warp.bilinear_to_square(*corners, mi.Point2f(*q.T.astype(np.float32)))
        their_back = np.array(c).T
    _agree(q, their_q, 2e-6)
    _agree(pdf, their_pdf, 2e-6)
    corners = tuple(np.array(CORNERS) / np.mean(CORNERS))
    _agree(warp.square_to_bilinear_pdf(*corners, q),
           _mi_call(mi, mi.warp.square_to_bilinear_pdf, kinds, *corners, q), 2e-6)
    _agree(warp.bilinear_to_square(*corners, q)[0], their_back, 2e-6)


@pytest.mark.mitsuba
@pytest.mark.parametrize("alpha", [0.3, 1.0])
def test_beckmann_agrees_with_mitsuba(mi, u_mi, alpha):
    # Mitsuba takes ln(1 - r^2) in float32, whose relative error grows as
    # eps / r^2 toward the pole (r the concentric radius): its points are
    # off by more than float32 precision within r < 0.1, where ours keep it
    # (see the float32 test above); compared outside.
    u = u_mi[:, :2]
    u = u[np.abs(u - 0.5).max(axis=1) > 0.05]
    d = warp.square_to_beckmann(u, alpha)
    _agree(d, _mi_call(mi, mi.warp.square_to_beckmann, ["p2", None], u, alpha), 1e-5)
    _agree(warp.square_to_beckmann_pdf(d, alpha),
           _mi_call(mi, mi.warp.square_to_beckmann_pdf, ["v3", None], d, alpha), 1e-6, 2e-5)
    _agree(warp.beckmann_to_square(d, alpha),
           _mi_call(mi, mi.warp.beckmann_to_square, ["v3", None], d, alpha), 1e-5)


@pytest.mark.mitsuba
@pytest.mark.parametrize("kappa", [0.5, 5.0, 50.0])
def test_von_mises_fisher_agrees_with_mitsuba(mi, u_mi, kappa):
    u = u_mi[:, :2]
    d = warp.square_to_von_mises_fisher(u, kappa)
    _agree(d, _mi_call(mi, mi.warp.square_to_von_mises_fisher, ["p2", None], u, kappa), 1e-5)
    _agree(warp.square_to_von_mises_fisher_pdf(d, kappa),
           _mi_call(mi, mi.warp.square_to_von_mises_fisher_pdf, ["v3", None], d, kappa),
           1e-6, 2e-5)
    _agree(warp.von_mises_fisher_to_square(d, kappa),
           _mi_call(mi, mi.warp.von_mises_fisher_to_square, ["v3", None], d, kappa), 1e-5)


@pytest.mark.mitsuba
@pytest.mark.parametrize("kappa", [0.5, 4.0])
def test_rough_fiber_agrees_with_mitsuba(mi, u_mi, kappa):
    # Densities compared where Mitsuba's I0 series is exact to float32
    # (c <= kappa <= 4); above, ours is the exact one (the chi-square tests).
    tangent = np.array([0.6, 0.0, 0.8])
    d = warp.square_to_rough_fiber(u_mi, WI, tangent, kappa)
    kinds = ["v3", "v3", None]
    _agree(d, _mi_call(mi, mi.warp.square_to_rough_fiber, ["p3"] + kinds, u_mi, WI, tangent,
                       kappa), 1e-5)
    _agree(warp.square_to_rough_fiber_pdf(d, WI, tangent, kappa),
           _mi_call(mi, mi.warp.square_to_rough_fiber_pdf, ["v3"] + kinds, d, WI, tangent,
                    kappa), 1e-6, 2e-5)


@pytest.mark.mitsuba
def test_lune_and_tangent_directions_agree_with_mitsuba(mi, u_mi):
    u = u_mi[:, :2]
    d = warp.square_to_uniform_spherical_lune(u, N1, N2)
    _agree(d, _mi_call(mi, mi.warp.square_to_uniform_spherical_lune, ["p2", "n3", "n3"],
                       u, N1, N2), 1e-5)
    _agree(warp.square_to_uniform_spherical_lune_pdf(d, N1, N2),
           _mi_call(mi, mi.warp.square_to_uniform_spherical_lune_pdf, ["v3", "n3", "n3"],
                    d, N1, N2), 1e-6)
    _agree(warp.uniform_spherical_lune_to_square(d, N1, N2),
           _mi_call(mi, mi.warp.uniform_spherical_lune_to_square, ["v3", "n3", "n3"],
                    d, N1, N2), 1e-5)
    n = np.array([0.2, -0.5, 0.84]) / np.linalg.norm([0.2, -0.5, 0.84])
    t = warp.interval_to_tangent_direction(n, u[:, 0])
    _agree(t, _mi_call(mi, mi.warp.interval_to_tangent_direction, ["n3", "f"], n, u[:, 0]), 1e-5)
    _agree(warp.tangent_direction_to_interval(n, t),
           _mi_call(mi, mi.warp.tangent_direction_to_interval, ["n3", "v3"], n, t), 1e-5)
