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
    (lambda: mcs.PiecewiseConstant1D([1, 2], 1.0, 1.0), ValueError, ["a < b"]),
    (lambda: mcs.PiecewiseConstant1D([1, 2], 0.0, INF), ValueError, ["a < b"]),
    (lambda: mcs.PiecewiseConstant2D([[1, INF]]), ValueError, ["values[0, 1] = inf"]),
    (lambda: mcs.PiecewiseConstant2D([[1]], ((0, 1), (1, 0))), ValueError, ["domain"]),
    # Sampling input: u outside [0, 1] or NaN, wrong shapes, bad indices.
    (lambda: mcs.Discrete1D([1, 2]).sample([0.5, 1.5]), ValueError, ["u[1] = 1.5", "[0, 1]"]),
    (lambda: mcs.Discrete1D([1, 2]).sample([[0.5, 0.5]]), ValueError, ["u must have shape (N,)"]),
    (lambda: mcs.AliasTable([1, 2]).sample([NAN]), ValueError, ["u[0] = NaN"]),
    (lambda: mcs.Discrete2D([[1, 2]]).sample([[0.5, -0.1]]), ValueError, ["u[0, 1] = -0.1"]),
    (lambda: mcs.Discrete2D([[1, 2]]).sample([0.5, 0.5, 0.5]), ValueError, ["(N, 2) or (2,)"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf([0, 2]), ValueError, ["i[1] = 2", "[0, 2)"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf(-1), ValueError, ["i = -1"]),
    (lambda: mcs.Discrete1D([1, 2]).pmf([0.5]), TypeError, ["i must be integers"]),
    (lambda: mcs.Discrete2D([[1, 2]]).pmf([[0, 5]]), ValueError, ["idx[0, 1] = 5", "[0, 2)"]),
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
     ["u must have shape (N, 2) or (2,)", "(1, 3)"]),
    # Phong: energy conservation, exponent, reflectances, directions.
    (lambda: mcs.Phong([0.5, 0.6, 0.2], [0.5, 0.5, 0.2], 10.0), ValueError,
     ["diffuse[1] + specular[1] = 1.1", "<= 1"]),
    (lambda: mcs.Phong(0.2, 0.3, -1.0), ValueError, ["exponent = -1", ">= 0"]),
    (lambda: mcs.Phong(0.2, 0.3, float("nan")), ValueError, ["exponent = NaN"]),
    (lambda: mcs.Phong([0.2, -0.1, 0.0], 0.3, 1.0), ValueError, ["diffuse[1] = -0.1"]),
    (lambda: mcs.Phong([0.2, 0.1], 0.3, 1.0), ValueError, ["diffuse must have shape (3,)"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0, selection="mean"), ValueError, ["selection"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0).sample([0, 0, 1.0], [[0.1, 0.2, 1.5]]), ValueError,
     ["u[0, 2] = 1.5"]),
    (lambda: mcs.Phong(0.2, 0.3, 1.0).sample([0, 0, 1.0], [[0.1, 0.2]]), ValueError,
     ["u must have shape (N, 3) or (3,)"]),
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
     ['sampling = "mitsuba"', "lat-long only"]),
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
