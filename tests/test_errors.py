"""Every bad input of DESIGN.md raises the right exception with a message
naming the argument (and the offending index or value): one table."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import warp

NAN, INF = float("nan"), float("inf")
U2 = [[0.1, 0.2], [0.3, 0.4]]
D3 = [[0.0, 0.0, 1.0]]

def _img(nan=None, value=None):
    """An (8, 16, 3) lat-long image, with a NaN at ``nan`` or ``value[3]`` at
    ``value[:3]``."""
    image = np.ones((8, 16, 3))
    if nan is not None:
        image[nan] = NAN
    if value is not None:
        image[value[:3]] = value[3]
    return image


def _read_only(shape):
    a = np.zeros(shape)
    a.flags.writeable = False
    return a


CASES = [
    # (call, exception, message fragments)
    # Discrete tables: NaN, inf, negative, all-zero, empty, wrong shapes.
    (lambda: mcs.Discrete1D([1, NAN, 2]), ValueError, ["weights[1] = NaN", ">= 0"]),
    (lambda: mcs.Discrete1D([1, 2, INF]), ValueError, ["weights[2] = inf"]),
    (lambda: mcs.Discrete1D([1, -0.5]), ValueError, ["weights[1] = -0.5"]),
    (lambda: mcs.Discrete1D([0, 0, 0]), ValueError, ["weights", "all zero"]),
    (lambda: mcs.Discrete1D([]), ValueError, ["weights", "empty"]),
    (lambda: mcs.Discrete1D([[1, 2]]), ValueError, ["weights must have shape (N,)", "(1, 2)"]),
    (lambda: mcs.Discrete1D("abc"), TypeError, ["weights"]),
    (lambda: mcs.AliasTable([1, NAN]), ValueError, ["weights[1] = NaN"]),
    (lambda: mcs.AliasTable([-1.0]), ValueError, ["weights[0] = -1"]),
    (lambda: mcs.AliasTable([0.0]), ValueError, ["all zero"]),
    (lambda: mcs.AliasTable([]), ValueError, ["empty"]),
    (lambda: mcs.Discrete2D([[1, 2], [3, -4]]), ValueError, ["weights[1, 1] = -4"]),
    (lambda: mcs.Discrete2D([[0, 0], [0, 0]]), ValueError, ["all zero"]),
    (lambda: mcs.Discrete2D([1, 2, 3]), ValueError, ["(rows, cols)", "(3,)"]),
    (lambda: mcs.Discrete2D(np.zeros((0, 3))), ValueError, ["empty"]),
    (lambda: mcs.PiecewiseConstant1D([1, NAN]), ValueError, ["values[1] = NaN"]),
    (lambda: mcs.PiecewiseConstant1D([1, 2], a=1.0, b=1.0), ValueError, ["a < b"]),
    (lambda: mcs.PiecewiseConstant1D([1, 2], a=0.0, b=INF), ValueError, ["a < b"]),
    (lambda: mcs.PiecewiseConstant2D([[1, INF]]), ValueError, ["values[0, 1] = inf"]),
    (lambda: mcs.PiecewiseConstant2D([[1]], domain=((0, 1), (1, 0))), ValueError, ["domain"]),
    # Sampling input: u outside [0, 1] or NaN, wrong shapes, bad indices.
    (lambda: mcs.Discrete1D([1, 2]).sample([0.5, 1.5]), ValueError, ["u[1] = 1.5", "[0, 1]"]),
    (lambda: mcs.Discrete1D([1, 2]).sample([[0.5, 0.5]]), ValueError, ["u must have shape (N,)"]),
    (lambda: mcs.AliasTable([1, 2]).sample([NAN]), ValueError, ["u[0] = NaN"]),
    (lambda: mcs.Discrete2D([[1, 2]]).sample([[0.5, -0.1]]), ValueError, ["u[0, 1] = -0.1"]),
    (lambda: mcs.Discrete2D([[1, 2]]).sample([0.5, 0.5, 0.5]), ValueError, ["(N, 2), (..., 2) or (2,)"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf([0, 2]), ValueError, ["i[1] = 2", "[0, 2)"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf(-1), ValueError, ["i = -1"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf([0.5]), TypeError, ["i must be integers"]),
    (lambda: mcs.Discrete2D([[1, 2]]).pmf([[0, 5]]), ValueError, ["idx[0, 1] = 5", "[0, 2)"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf(2**70), ValueError,
     [f"i = {2**70}", "must be an index in [0, 2)"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf(np.uint64(2**63)), ValueError, [f"i = {2**63}"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf([0, -2**70]), ValueError, [f"i = {-2**70}"]),
    (lambda: mcs.PiecewiseConstant1D([1, 2]).sample([2.0]), ValueError, ["u[0] = 2"]),
    (lambda: mcs.PiecewiseConstant1D([1, 2]).invert([0.5, 1.5]), ValueError,
     ["x[1] = 1.5", "[0, 1]"]),
    (lambda: mcs.PiecewiseConstant1D([1, 2]).pdf([NAN]), ValueError, ["x[0] = NaN"]),
    (lambda: mcs.PiecewiseConstant2D([[1, 2]]).invert([[0.5, 2.0]]), ValueError,
     ["xy[0, 1] = 2", "[0, 1]"]),
    # Warps: exponent < 0, cos_cutoff outside [-1, 1), NaN points.
    (lambda: warp.square_to_cosine_power_hemisphere(U2, -1.0), ValueError,
     ["exponent = -1", ">= 0"]),
    (lambda: warp.square_to_cosine_power_hemisphere_pdf(D3, NAN), ValueError, ["exponent = NaN"]),
    (lambda: warp.interval_to_power([0.5], -0.5), ValueError, ["exponent = -0.5"]),
    (lambda: warp.square_to_uniform_cone(U2, 1.5), ValueError, ["cos_cutoff = 1.5", "[-1, 1)"]),
    (lambda: warp.square_to_uniform_cone_pdf(D3, -1.01), ValueError, ["cos_cutoff = -1.01"]),
    (lambda: warp.square_to_uniform_disk([[0.1, NAN]]), ValueError, ["u[0, 1] = NaN"]),
    (lambda: warp.square_to_uniform_sphere_pdf([[0.0, INF, 0.0]]), ValueError, ["x[0, 1] = inf"]),
    (lambda: warp.square_to_uniform_sphere([[0.1, 0.2, 0.3]]), ValueError,
     ["u must have shape (N, 2), (..., 2) or (2,)", "(1, 3)"]),
    # Phong: energy conservation, exponent, reflectances, directions.
    (lambda: mcs.Phong([0.5, 0.6, 0.2], [0.5, 0.5, 0.2], 10.0), ValueError,
     ["diffuse[1] + specular[1] = 1.1", "<= 1"]),
    (lambda: mcs.Phong(0.2, 0.3, -1.0), ValueError, ["exponent = -1", "[0, 1e30]"]),
    (lambda: mcs.Phong(0.2, 0.3, 1e31), ValueError, ["exponent = 1000000000", "[0, 1e30]"]),
    (lambda: mcs.Phong(0.2, 0.3, float("nan")), ValueError, ["exponent = NaN"]),
    (lambda: mcs.Phong([0.2, -0.1, 0.0], 0.3, 1.0), ValueError, ["diffuse[1] = -0.1"]),
    (lambda: mcs.Phong([0.2, 0.1], 0.3, 1.0), ValueError, ["diffuse must have shape (3,)"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0, selection="mean"), ValueError, ["selection"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0).sample([0, 0, 1.0], [[0.1, 0.2, 1.5]]), ValueError,
     ["u[0, 2] = 1.5"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0).sample([0, 0, 1.0], [[0.1, 0.2]]), ValueError,
     ["u must have shape (N, 3), (..., 3) or (3,)"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0).eval(np.ones((2, 3)), np.ones((3, 3))), ValueError,
     ["wo", "2 rows"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0).pdf([0, NAN, 1.0], [0, 0, 1.0]), ValueError,
     ["wi[1] = NaN"]),
    # Frames.
    (lambda: mcs.Frame([0, 0, 0]), ValueError, ["normal", "non-zero"]),
    (lambda: mcs.Frame([[0, 0, 1], [NAN, 0, 1]]), ValueError, ["normal[1]"]),
    (lambda: mcs.Frame([[0, 0, 1], [0, 1, 0]]).to_local(np.ones((3, 3))), ValueError,
     ["v must have shape (2, 3)"]),
    # Environment maps: bad texels, shapes, options, files and inputs.
    (lambda: mcs.EnvMap(_img(nan=(2, 3, 1))), ValueError, ["image[2, 3, 1] = NaN", ">= 0"]),
    (lambda: mcs.EnvMap(_img(value=(1, 0, 0, INF))), ValueError, ["image[1, 0, 0] = inf"]),
    (lambda: mcs.EnvMap(_img(value=(0, 5, 2, -1.0))), ValueError, ["image[0, 5, 2] = -1"]),
    (lambda: mcs.EnvMap(np.ones((6, 4, 4, 3)), mapping="cube").__class__(
        np.full((6, 4, 4, 3), NAN), mapping="cube"), ValueError, ["image[0, 0, 0, 0] = NaN"]),
    (lambda: mcs.EnvMap(np.ones((4, 8))), ValueError, ["image must have shape (H, W, 3)", "(4, 8)"]),
    (lambda: mcs.EnvMap(np.ones((4, 8, 3)), mapping="angular"), ValueError,
     ["image must have shape (R, R, 3)"]),
    (lambda: mcs.EnvMap(np.ones((4, 8, 3)), mapping="cube"), ValueError, ["(6, R, R, 3)"]),
    (lambda: mcs.EnvMap(np.ones((0, 8, 3))), ValueError, ["image must have shape"]),
    (lambda: mcs.EnvMap(_img(), mapping="polar"), ValueError, ['mapping = "polar"', "latlong"]),
    (lambda: mcs.EnvMap(_img(), sampling="fast"), ValueError, ['sampling = "fast"']),
    (lambda: mcs.EnvMap(np.ones((4, 4, 3)), mapping="angular", sampling="mitsuba"), ValueError,
     ['sampling = "mitsuba"', "for lat-long maps"]),
    (lambda: mcs.EnvMap(np.ones((6, 4, 4, 3)), mapping="cube", sampling="luminance"), ValueError,
     ['sampling = "luminance"', "for lat-long maps", "piecewise"]),
    (lambda: mcs.EnvMap(_img(), scale=-2.0), ValueError, ["scale = -2", ">= 0"]),
    (lambda: mcs.EnvMap(_img(), scale=NAN), ValueError, ["scale = NaN"]),
    (lambda: mcs.EnvMap(_img(), to_world=np.diag([2.0, 1, 1])), ValueError,
     ["to_world", "rotation"]),
    (lambda: mcs.EnvMap(_img(), to_world=np.ones((2, 2))), ValueError,
     ["to_world must have shape (3, 3) or (4, 4)"]),
    (lambda: mcs.EnvMap(_img(), to_world=[[1, 0, 0], [0, NAN, 0], [0, 0, 1]]), ValueError,
     ["to_world[1, 1] = NaN"]),
    (lambda: mcs.EnvMap.load("/nonexistent/sky.exr"), OSError, ["/nonexistent/sky.exr"]),
    (lambda: mcs.EnvMap(_img()).sample([[0.5, NAN]]), ValueError, ["u[0, 1] = NaN"]),
    (lambda: mcs.EnvMap(_img()).sample([0.5, 1.5, 0.1]), ValueError, ["u must have shape (N, 2)"]),
    (lambda: mcs.EnvMap(_img()).eval([[0, 1, 0], [INF, 0, 0]]), ValueError, ["d[1, 0] = inf"]),
    (lambda: mcs.EnvMap(_img()).pdf([[0, 1]]), ValueError, ["d must have shape (N, 3)"]),
    (lambda: mcs.EnvMap(_img()).uv_to_dir([0.5, 1.5]), ValueError, ["uv[1] = 1.5"]),
    (lambda: mcs.EnvMap(_img()).convert("cube", 0), ValueError, ["resolution = 0"]),
    (lambda: mcs.EnvMap(_img()).convert("cube", 2.5), TypeError, ["resolution"]),
    (lambda: mcs.EnvMap(_img()).convert("latlong", (-1, 8)), ValueError, ["resolution = -1"]),
    (lambda: mcs.EnvMap(_img()).convert("latlong", (4, 2**70)), ValueError,
     [f"resolution = {2**70}"]),
    # Options after the essential positional arguments are keyword-only.
    (lambda: mcs.EnvMap(_img(), "latlong"), TypeError, ["positional"]),
    (lambda: mcs.PiecewiseConstant1D([1, 2], 0.0, 2.0), TypeError, ["positional"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0, "max"), TypeError, ["positional"]),
    (lambda: mcs.estimators.irradiance(mcs.EnvMap(_img()), [0, 1, 0], 10, "mis"), TypeError,
     ["positional"]),
    # Named options: one message for all, listing the choices.
    (lambda: warp.square_to_cosine_hemisphere(U2, method="spiral"), ValueError,
     ['method = "spiral"', 'must be "concentric" or "polar"']),
    (lambda: mcs.estimators.irradiance(mcs.EnvMap(_img()), [0, 1, 0], 10, strategy="bsdf"),
     ValueError, ['strategy = "bsdf"', '"uniform", "cosine", "emitter" or "mis"']),
    (lambda: mcs.estimators.irradiance(mcs.EnvMap(_img()), [0, 1, 0], 10, heuristic="max"),
     ValueError, ['heuristic = "max"', '"power" or "balance"']),
    # Seeds: an int in [0, 2**64), None or a numpy Generator.
    (lambda: mcs.Rng(seed=2**64), ValueError, [f"seed = {2**64}"]),
    (lambda: mcs.Rng(seed=-1), ValueError, ["seed = -1"]),
    (lambda: mcs.Rng(seed="a"), TypeError, ["seed must be an integer, None or a numpy"]),
    (lambda: mcs.Rng(stream=2**63), ValueError, [f"stream = {2**63}"]),
    (lambda: mcs.uniform(4, seed=1.5), TypeError, ["seed must be an int"]),
    (lambda: mcs.uniform(4, dim=2**70), ValueError, [f"dim = {2**70}"]),
    (lambda: mcs.estimators.irradiance(mcs.EnvMap(_img()), [0, 1, 0], 10, seed=2**64),
     ValueError, [f"seed = {2**64}"]),
    # Integers of any size: ValueError, never OverflowError.
    (lambda: mcs.set_num_threads(2**70), ValueError, [f"n = {2**70}"]),
    (lambda: mcs.estimators.irradiance(mcs.EnvMap(_img()), [0, 1, 0], 2**70), ValueError,
     [f"n = {2**70}"]),
    (lambda: mcs.Rng().random(2**70), ValueError, [f"shape = {2**70}"]),
    # out= arrays: each says what is wrong with them.
    (lambda: warp.square_to_uniform_disk(np.full((8, 2), 0.5), out=np.zeros((8, 2), np.float32)),
     TypeError, ["out must have dtype float64, got float32"]),
    (lambda: warp.square_to_uniform_disk(np.full((8, 2), 0.5), out=[[0.0, 0.0]] * 8), TypeError,
     ["out must be a numpy array, got list"]),
    (lambda: warp.square_to_uniform_disk(np.full((8, 2), 0.5), out=np.zeros((8, 3))), ValueError,
     ["out must have shape (8, 2)", "got (8, 3)"]),
    (lambda: warp.square_to_uniform_disk(np.full((8, 2), 0.5), out=np.zeros((8, 4))[:, ::2]),
     ValueError, ["out must be C-ordered (C-contiguous"]),
    (lambda: warp.square_to_uniform_disk(np.full((8, 2), 0.5), out=_read_only((8, 2))),
     ValueError, ["out is read-only"]),
    (lambda: (lambda u: warp.square_to_uniform_disk(u, out=u))(np.full((8, 2), 0.5)), ValueError,
     ["out must not share memory"]),
    (lambda: mcs.EnvMap(_img()).sample(np.full((4, 2), 0.5), out=(
        np.zeros((4, 3)), np.zeros(4, np.float32), np.zeros((4, 3)))), TypeError,
     ["out[1] must have dtype float64, got float32"]),
    (lambda: mcs.EnvMap(_img()).pdf(np.ones((4, 3)), out=np.zeros((4, 3))), ValueError,
     ["out must have shape (4,)", "got (4, 3)"]),
    # Batches that do not broadcast: the refusal says how to fix the call.
    (lambda: mcs.Phong(0.2, 0.3, 1.0).sample(np.tile([0, 0, 1.0], (2, 1)), np.full((5, 3), 0.5)),
     ValueError, ["wi has 2 rows and u has 5", "single row"]),
    (lambda: mcs.mis.balance_heuristic(np.ones(3), np.ones(4)), ValueError,
     ["pdf_a has 3 rows and pdf_b has 4"]),
    (lambda: mcs.Frame([[0, 0, 1], [0, 1, 0]]).to_world(np.ones((3, 3))), ValueError,
     ["v must have shape (2, 3) or (3,), one row per normal"]),
    # Rejection sampling: a pdf callable returning negative values, values
    # above the bound, NaN; bad bound, domain or n.
    (lambda: mcs.rejection_sample(lambda x: x - 0.5, 1.0, (0, 1), 10), ValueError,
     ["pdf(", "must lie in [0, bound = 1.0]"]),
    (lambda: mcs.rejection_sample(lambda x: 2 * np.ones(len(x)), 1.0, (0, 1), 10), ValueError,
     ["= 2.0", "bound = 1.0"]),
    (lambda: mcs.rejection_sample(lambda x: np.full(len(x), NAN), 1.0, (0, 1), 10), ValueError,
     ["= nan"]),
    (lambda: mcs.rejection_sample(lambda x: x, -1.0, (0, 1), 10), ValueError, ["bound = -1"]),
    (lambda: mcs.rejection_sample(lambda x: x, 1.0, (1, 0), 10), ValueError, ["domain"]),
    (lambda: mcs.rejection_sample(lambda x: x, 1.0, (0, 1), -3), ValueError, ["n = -3"]),
    (lambda: mcs.rejection_sample(lambda x: np.zeros(len(x)), 1.0, (0, 1), 1), ValueError,
     ["no proposal accepted"]),
]


@pytest.mark.parametrize("call,exc,fragments", CASES, ids=range(len(CASES)))
def test_bad_input_raises(call, exc, fragments):
    with pytest.raises(exc) as info:
        call()
    for fragment in fragments:
        assert fragment in str(info.value), str(info.value)


def test_max_depth_of_any_size_is_a_value_error():
    from scenes import diffuse_sphere_under_sky, sensor

    d = dict(diffuse_sphere_under_sky(mcs.EnvMap(_img())), sensor=sensor(width=4, height=3))
    scene = mcs.Scene.from_mitsuba(d)
    for depth in [2**70, -2**70, 2**32, -2]:
        with pytest.raises(ValueError, match=f"max_depth = {depth}: must be -1"):
            mcs.render(scene, 1, max_depth=depth, progress=False)
    assert mcs.render(scene, 1, max_depth=2**32 - 1, progress=False).image.shape == (3, 4, 3)


def test_a_single_row_broadcasts():
    """A single row (1, k) is used for every row of the other input of a
    pair, as a (k,) point is (numpy's broadcasting)."""
    phong = mcs.Phong(0.2, 0.3, 10.0)
    u = mcs.uniform(5, 3, seed=1)
    wi = np.array([0.0, 0.6, 0.8])
    one = phong.sample(wi, u)
    row = phong.sample(wi[None, :], u)
    assert np.array_equal(one.wo, row.wo) and np.array_equal(one.pdf, row.pdf)
    assert np.array_equal(phong.eval(wi[None, :], one.wo), phong.eval(wi, one.wo))
    assert mcs.mis.power_heuristic([1.0], np.ones(4)).shape == (4,)
    normal, v = [0.3, 0.4, 0.5], [1.0, 2.0, 3.0]
    frames = mcs.Frame(np.tile(normal, (4, 1)))
    assert np.array_equal(frames.to_world([v]), np.tile(mcs.Frame(normal).to_world(v), (4, 1)))


def test_seeds_mean_the_same_everywhere():
    """The default seed is 0; None draws fresh entropy; a Generator draws a
    seed from itself, so a seeded Generator reproduces."""
    assert mcs.Rng().seed == 0 and np.array_equal(mcs.uniform(3), mcs.uniform(3, seed=0))
    assert mcs.Rng(None).seed != mcs.Rng(None).seed
    a = mcs.uniform(3, seed=np.random.default_rng(5))
    assert np.array_equal(a, mcs.uniform(3, seed=np.random.default_rng(5)))
    env = mcs.EnvMap(_img())
    e = mcs.estimators.irradiance(env, [0, 1, 0], 100, strategy="envmap")
    assert e.strategy == "emitter"
    same = mcs.estimators.irradiance(env, [0, 1, 0], 100, strategy="emitter", seed=0)
    assert np.array_equal(e.value, same.value)
