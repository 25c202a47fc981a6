"""Connections to the camera (``Scene.sample_sensor``, Mitsuba's
``sensor.sample_direction``): the same numbers as Mitsuba's, and a light
tracing estimate built on them equal to the path-traced render."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats

W, H = 40, 24


def camera(kind="perspective", fov_axis="x", **kw):
    d = {"type": kind, "fov": 45.0, "fov_axis": fov_axis, "near_clip": 0.5, "far_clip": 50.0,
         "to_world": mcs.look_at([0.5, 1.0, -4.0], [0.2, 0.3, 0.0], [0, 1, 0]),
         "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"}}}
    if kind == "thinlens":
        d.update(aperture_radius=0.15, focus_distance=4.0)
    d.update(kw)
    return d


def light_scene(sensor, radiance=2.0):
    """An area light (a rectangle 1.6 × 1.0, facing the camera, partly
    outside the view) in front of a black sky."""
    # Mitsuba's rectangle turned 180° about y: its normal is -z.
    m = np.array([[-0.8, 0, 0, 0.9], [0, 0.5, 0, 0.5], [0, 0, -1, 0.3], [0, 0, 0, 1.0]])
    return {"type": "scene", "sensor": sensor,
            "light": {"type": "rectangle", "to_world": m,
                      "emitter": {"type": "area", "radiance": radiance}}}, m


@pytest.mark.mitsuba
@pytest.mark.parametrize("kind, fov_axis", [("perspective", "x"), ("perspective", "smaller"),
                                            ("thinlens", "y")])
@pytest.mark.parametrize("variant", [None, "scalar_rgb"], ids=["suite", "scalar_rgb"])
def test_sample_sensor_is_mitsubas(mi, kind, fov_axis, variant):
    """The same numbers as Mitsuba's, in the suite's variant and in the
    scalar one (the fallback where no libLLVM runs)."""
    g = np.random.default_rng(3)
    x = g.uniform([-3, -2, -1], [3, 3, 6], (4000, 3))
    u = g.random((4000, 2))
    d, _ = light_scene(camera(kind, fov_axis))
    ours = mcs.Scene.from_mitsuba(d).sample_sensor(x, u)
    with mcs.mitsuba.variant_set(variant) as m:
        cam = camera(kind, fov_axis)
        cam["to_world"] = m.ScalarTransform4f(cam["to_world"].tolist())
        uv, d, dist, pdf, w = _mitsuba_sensor_samples(m, m.load_dict(cam), x, u)
    valid = pdf > 0
    assert 500 < valid.sum() < 3900
    assert np.array_equal(valid, ours.pdf > 0)
    assert np.allclose(ours.pixel[valid], uv[valid], atol=2e-3)
    assert np.allclose(ours.direction[valid], d[valid], atol=1e-5)
    assert np.allclose(ours.distance[valid], dist[valid], rtol=1e-5)
    assert np.allclose(ours.pdf[valid], pdf[valid], rtol=1e-4)
    assert np.allclose(ours.weight[valid], w[valid], rtol=1e-4)


def _mitsuba_sensor_samples(mi, sensor, x, u):
    """Mitsuba's ``sensor.sample_direction`` from each point ``x`` (n, 3)
    with the numbers ``u`` (n, 2): the film positions (n, 2), directions
    (n, 3), distances, densities and the weights' first channel (n): in
    one call in a JIT variant, one call per row in a scalar variant (the
    fallback where no libLLVM runs), whose points are single points."""
    if not mi.variant().startswith("scalar"):
        it = mi.Interaction3f()
        it.p = mi.Point3f(*x.T)
        ds, weight = sensor.sample_direction(it, mi.Point2f(*u.T))
        w = np.asarray(weight)
        return (np.asarray(ds.uv).T, np.asarray(ds.d).T, np.asarray(ds.dist),
                np.asarray(ds.pdf), np.ravel(w.T[:, 0] if w.ndim == 2 else w))
    rows = []
    for xi, ui in zip(x, u):
        it = mi.Interaction3f()
        it.p = mi.Point3f(*xi)
        ds, weight = sensor.sample_direction(it, mi.Point2f(*ui))
        rows.append((list(ds.uv), list(ds.d), ds.dist, ds.pdf, weight[0]))
    return tuple(np.array(column, dtype=np.float64) for column in zip(*rows))


@pytest.mark.parametrize("kind", ["perspective", "thinlens"])
def test_light_tracing_with_sample_sensor_matches_the_render(kind):
    """Points drawn uniformly on the light, each connected to the camera:
    pixel j's mean is W·H·A·L·cos·weight averaged over the points that
    land in it (A the light's area), the estimator Mitsuba's particle
    tracer makes of directly visible emitters. Its per-pixel z-test
    against the path-traced render (emission only) passes; the weight
    without its 1/cos³θ, rescaled to the same mean, is rejected."""
    d, m = light_scene(camera(kind))
    scene = mcs.Scene.from_mitsuba(d)
    r = mcs.render(scene, 256, integrator="path", max_depth=1, seed=4)
    g = np.random.default_rng(5)
    n = 4_000_000
    local = g.uniform(-1, 1, (n, 2))
    x = local[:, :1] * m[:3, 0] + local[:, 1:] * m[:3, 1] + m[:3, 3]
    normal = np.cross(m[:3, 0], m[:3, 1])
    area = 4 * np.linalg.norm(normal)
    normal /= np.linalg.norm(normal)
    s = scene.sample_sensor(x, g.random((n, 2)))
    cos = np.maximum(s.direction @ normal, 0)

    def estimate(weight):
        c = 2.0 * area * cos * weight * W * H
        px = np.clip(np.floor(s.pixel).astype(int), [0, 0], [W - 1, H - 1])
        j = np.where(s.pdf > 0, px[:, 1] * W + px[:, 0], 0)
        c = np.where(s.pdf > 0, c, 0)
        mean = np.bincount(j, c, W * H) / n
        var = (np.bincount(j, c * c, W * H) / n - mean**2) / (n - 1)
        return mean.reshape(H, W), var.reshape(H, W)

    mean, var = estimate(s.weight)
    t = stats.image_ztest(r.luminance, r.luminance_variance, mean, var)
    assert t.passed, t.message
    # Power: the weight without the film's 1/cos³θ (θ from the optical
    # axis, 11° to 25° here), scaled to the same image mean.
    axis = np.array([0.2, 0.3, 0.0]) - [0.5, 1.0, -4.0]
    cos_axis = -s.direction @ (axis / np.linalg.norm(axis))
    wrong, wvar = estimate(s.weight * cos_axis**3)
    scale = mean.sum() / wrong.sum()
    t = stats.image_ztest(r.luminance, r.luminance_variance, wrong * scale, wvar * scale**2)
    assert not t.passed


def test_sample_sensor_checks_its_input():
    d, _ = light_scene(camera())
    s = mcs.Scene.from_mitsuba(d)
    with pytest.raises(ValueError, match="u"):
        s.sample_sensor([0, 0, 0], [0.5, 1.5])
    with pytest.raises(ValueError, match="x"):
        s.sample_sensor([0, np.nan, 0], [0.5, 0.5])
    with pytest.raises(ValueError, match="x"):
        s.sample_sensor(np.zeros((3, 2)), np.zeros((3, 2)))
    # Behind the camera or past the far clip: no connection, all zeros.
    out = s.sample_sensor([[0.5, 1.0, -10.0], [0.2, 0.3, 200.0]], [[0.5, 0.5]] * 2)
    assert not out.pdf.any() and not out.weight.any() and not out.pixel.any()
