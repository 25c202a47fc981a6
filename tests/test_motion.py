"""Motion blur: shapes and the camera moving during the shutter, against
unbiased oracles computed here (the exact ray–shape test at the sampled
times), each strategy alone, and the degenerate cases (no motion, a closed
shutter) against still scenes."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats

W, H, FOV = 24, 12, 40.0
BLACK = {"type": "diffuse", "reflectance": 0.0}


def translate(x, y=0.0, z=0.0):
    m = np.eye(4)
    m[:3, 3] = x, y, z
    return m


def sensor(**kw):
    d = {"type": "perspective", "fov": FOV, "fov_axis": "x",
         "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"}},
         "shutter_open": 0.0, "shutter_close": 1.0, **kw}
    return {k: v for k, v in d.items() if v is not None}


def sky_scene(*shapes, **sensor_keys):
    d = {"type": "scene", "sky": {"type": "constant", "radiance": 1.0},
         "sensor": sensor(**sensor_keys)}
    d.update({f"s{i}": s for i, s in enumerate(shapes)})
    return d


def film_rays(n, seed):
    """``n`` unit camera directions uniform over each pixel's film area
    (pinhole at the origin looking down +z, x to the image's left):
    (H, W, n, 3)."""
    g = np.random.default_rng(seed)
    x = (np.arange(W)[None, :, None] + g.random((H, W, n))) / W
    y = (np.arange(H)[:, None, None] + g.random((H, W, n))) / H
    tx = np.tan(np.radians(FOV) / 2)
    d = np.stack([(1 - 2 * x) * tx, (1 - 2 * y) * tx * H / W, np.ones_like(x)], axis=-1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def oracle(seen, n=4096, seed=0):
    """Each pixel's expected sky fraction and the variance of that
    estimate, from ``n`` film positions per pixel; ``seen(d)`` gives the
    fraction of the shutter time during which direction d sees the sky."""
    s = seen(film_rays(n, seed))
    return s.mean(axis=-1), s.var(axis=-1, ddof=1) / n


def moving_sphere_seen(c0, v, r):
    """The time fraction a ray d misses a sphere of radius r whose centre
    moves from c0 to c0 + v: |w0 + τ wv|² ≤ r², with w the centre's part
    across d, solved for τ exactly and cut to [0, 1]."""
    def seen(d):
        c0_, v_ = np.asarray(c0, float), np.asarray(v, float)
        w0 = c0_ - (d @ c0_)[..., None] * d
        wv = v_ - (d @ v_)[..., None] * d
        a, b, c = (wv * wv).sum(-1), 2 * (w0 * wv).sum(-1), (w0 * w0).sum(-1) - r * r
        disc = b * b - 4 * a * c
        root = np.sqrt(np.maximum(disc, 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            lo, hi = (-b - root) / (2 * a), (-b + root) / (2 * a)
        blocked = np.where(disc > 0, np.clip(np.minimum(hi, 1) - np.maximum(lo, 0), 0, 1), 0)
        # A still sphere (v = 0) blocks the ray all the time or never.
        return 1 - np.where(a > 0, blocked, c <= 0)
    return seen


SPHERE = {"type": "sphere", "center": [-1.0, 0.0, 5.0], "radius": 0.6, "bsdf": BLACK,
          "to_world_end": translate(2.0)}


def ztest(r, expected, var):
    t = stats.image_ztest(r.luminance, r.luminance_variance, expected, var)
    assert t.passed, t.message
    return t


def test_moving_sphere_matches_the_exact_time_fraction():
    """A black sphere sliding across a white sky: each pixel is the
    fraction of its area × shutter time whose ray misses the sphere.
    Power: the still sphere (time not sampled), a path half as long and a
    path turned 8.5° off are rejected."""
    r = mcs.render(mcs.Scene.from_mitsuba(sky_scene(SPHERE)), 1024, integrator="path",
                   max_depth=1, seed=3)
    expected, var = oracle(moving_sphere_seen([-1, 0, 5], [2, 0, 0], 0.6))
    ztest(r, expected, var)
    for wrong in ([0, 0, 0], [1, 0, 0], [2, 0.3, 0]):
        e, v = oracle(moving_sphere_seen([-1, 0, 5], wrong, 0.6), seed=1)
        assert not stats.image_ztest(r.luminance, r.luminance_variance, e, v).passed


def test_rotating_bar_turns_by_slerp():
    """A black bar (a cube scaled 1.6 × 0.12 × 0.12) at z = 6 turning by 90°
    about the view axis during the shutter: the oracle draws a time per
    film position and tests the ray against the bar turned by 90° τ (the
    exact slab test in the bar's frame). Interpolating the matrices
    instead of the rotation is rejected."""
    scale = np.diag([1.6, 0.12, 0.12, 1.0])  # the cube is [-1, 1]^3

    def turned(angle):
        c, s = np.cos(angle), np.sin(angle)
        return translate(0, 0, 6) @ np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0],
                                               [0, 0, 0, 1.0]]) @ scale

    bar = {"type": "cube", "bsdf": BLACK, "to_world": turned(0.0),
           "to_world_end": turned(np.pi / 2)}
    r = mcs.render(mcs.Scene.from_mitsuba(sky_scene(bar)), 1024, integrator="path",
                   max_depth=1, seed=4)

    def bar_seen(angle, scale):
        """The bar turned by angle(τ) and scaled across the view by
        scale(τ) at a time τ drawn per film position."""
        def seen(d):
            tau = np.random.default_rng(7).random(d.shape[:-1])
            a, k = angle(tau), scale(tau)
            # The ray in the bar's frame: turned back by a, scaled back.
            x = np.cos(a) * d[..., 0] + np.sin(a) * d[..., 1]
            y = -np.sin(a) * d[..., 0] + np.cos(a) * d[..., 1]
            local = np.stack([x / (1.6 * k), y / (0.12 * k), d[..., 2] / 0.12], axis=-1)
            o = np.array([0, 0, -6 / 0.12])
            with np.errstate(divide="ignore", invalid="ignore"):
                t1, t2 = (-1 - o) / local, (1 - o) / local
            near = np.minimum(t1, t2).max(axis=-1)
            far = np.maximum(t1, t2).min(axis=-1)
            return 1.0 - (near <= far)
        return seen

    ztest(r, *oracle(bar_seen(lambda t: np.pi / 2 * t, lambda t: np.ones_like(t))))
    # Linear interpolation of the matrices, (1 − τ) R(0) + τ R(90°) = k R(φ)
    # with k = |(1 − τ, τ)| and φ = atan2(τ, 1 − τ): a bar 0.71 as long at
    # τ = ½, turning at another pace.
    e, v = oracle(bar_seen(lambda t: np.arctan2(t, 1 - t), lambda t: np.hypot(1 - t, t)))
    assert not stats.image_ztest(r.luminance, r.luminance_variance, e, v).passed


def test_moving_camera_is_the_scene_moving_the_other_way():
    """The camera sliding by +2 along x past a still sphere sees what a
    still camera sees of the sphere sliding by −2 (z-test of two renders)."""
    still = dict(SPHERE, center=[1.0, 0.0, 5.0], to_world_end=np.eye(4))
    cam = mcs.render(mcs.Scene.from_mitsuba(sky_scene(still, to_world_end=translate(2.0))),
                     1024, integrator="path", max_depth=1, seed=5)
    moving = dict(SPHERE, center=[1.0, 0.0, 5.0], to_world_end=translate(-2.0))
    ref = mcs.render(mcs.Scene.from_mitsuba(sky_scene(moving)), 1024, integrator="path",
                     max_depth=1, seed=6)
    t = stats.render_ztest(cam, ref)
    assert t.passed, t.message
    expected, var = oracle(moving_sphere_seen([1, 0, 5], [-2, 0, 0], 0.6))
    ztest(cam, expected, var)


def test_two_movers_and_a_still_sphere_each_keep_their_material():
    """Three diffuse spheres of albedo 0.2, 0.5 and 0.8 under a uniform
    sky of radiance 1: a sphere alone under it reflects its albedo, so
    each pixel is about the time and area fraction of sky (1) and of each
    sphere (its albedo); the spheres hide a little sky from each other
    (a few percent at most here), so pixels are compared within 5
    standard errors plus 0.03. Two of them move (translating, and translating while
    turning about its centre), the third stays; the oracle draws a time
    per film position and finds the first sphere on the ray. The moving
    spheres' materials swapped (a hit credited to the other moving
    shape) are off by up to 0.6 and rejected."""
    # Placed by to_world about their own centre (the origin of their
    # frame), so that the interpolated translation is the centre's path.
    turn = np.array([[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1.0]])
    balls = [
        {"type": "sphere", "center": [-1.7, 0.3, 6.0], "radius": 0.3,
         "bsdf": {"type": "diffuse", "reflectance": 0.2}, "to_world_end": translate(0.5, 0.3)},
        {"type": "sphere", "center": [0.0, 0.0, 6.0], "radius": 0.3,
         "bsdf": {"type": "diffuse", "reflectance": 0.5}},
        {"type": "sphere", "radius": 0.3, "to_world": translate(1.4, 0.4, 6.0),
         "bsdf": {"type": "diffuse", "reflectance": 0.8},
         "to_world_end": translate(1.4, -0.3, 6.0) @ turn},
    ]
    d = sky_scene(*balls)
    r = mcs.render(mcs.Scene.from_mitsuba(d), 1024, integrator="path", max_depth=2, seed=8)

    def seen(albedo):
        def value(d):
            tau = np.random.default_rng(11).random(d.shape[:-1])[..., None]
            best, out = np.full(d.shape[:-1], np.inf), np.ones(d.shape[:-1])
            centres = [np.array([-1.7, 0.3, 6.0]) + tau * [0.5, 0.3, 0],
                       np.array([0.0, 0.0, 6.0]) + 0 * tau,
                       np.array([1.4, 0.4, 6.0]) - tau * [0, 0.7, 0]]
            for c, radius, a in zip(centres, [0.3, 0.3, 0.3], albedo):
                h = (d * c).sum(-1)
                disc = h * h - (c * c).sum(-1) + radius * radius
                t = h - np.sqrt(np.maximum(disc, 0))
                hit = (disc > 0) & (t < best)
                best, out = np.where(hit, t, best), np.where(hit, a, out)
            return out
        return value

    def close(albedo):
        e, v = oracle(seen(albedo))
        return np.abs(r.luminance - e) < 5 * np.sqrt(r.luminance_variance + v) + 0.03

    assert close([0.2, 0.5, 0.8]).all()
    assert (~close([0.8, 0.5, 0.2])).sum() > 20


def test_spinning_sphere_shades_as_a_still_one():
    """A diffuse sphere turning by 90° about its centre during the shutter
    is the still sphere, shaded by its normals: under a small light above,
    its render is z-test-equal to the still one's (normals left in the
    sphere's frame at shutter_open would turn the lit side 90° away)."""
    def scene(end):
        d = lit_scene()
        d["ball"].update(center=[0.0, 0.0, 0.0], to_world=translate(0, 0.5, 0),
                         to_world_end=translate(0, 0.5, 0) @ end)
        return mcs.Scene.from_mitsuba(d)

    turn = np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1.0]])
    spinning = mcs.render(scene(turn), 512, integrator="direct", seed=1)
    still = mcs.render(scene(np.eye(4)), 512, integrator="direct", seed=2)
    t = stats.render_ztest(spinning, still)
    assert t.passed, t.message


def lit_scene(**sensor_keys):
    """A diffuse sphere sliding over a diffuse floor under a small square
    light: its shadow is found by shadow rays (emitter sampling) and by
    BSDF-sampled rays alike, both at the sample's time."""
    to_world = mcs.look_at([0, 3, 4], [0, 0, 0], [0, 1, 0])
    # Mitsuba's rectangle (normal +z) turned to face down (-y) at y = 2.
    light = np.array([[0.3, 0, 0, 0], [0, 0, -0.3, 2.0], [0, 0.3, 0, 0], [0, 0, 0, 1.0]])
    floor = np.diag([3.0, 3.0, 3.0, 1.0]) @ np.array(
        [[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1.0]])
    return {"type": "scene",
            "sensor": sensor(to_world=to_world, **sensor_keys),
            "light": {"type": "rectangle", "to_world": light,
                      "emitter": {"type": "area", "radiance": 30.0}},
            "floor": {"type": "rectangle", "to_world": floor,
                      "bsdf": {"type": "diffuse", "reflectance": 0.6}},
            "ball": {"type": "sphere", "center": [-0.6, 0.5, 0.0], "radius": 0.35,
                     "bsdf": {"type": "diffuse", "reflectance": 0.4},
                     "to_world_end": translate(1.2)}}


def test_each_strategy_sees_the_moving_shadow():
    """Direct light by emitter sampling alone, BSDF sampling alone and MIS
    of a scene whose moving sphere shadows the floor: pairwise z-test
    equal (a shadow ray traced at another time than its path would move
    the emitter-sampled shadow)."""
    s = mcs.Scene.from_mitsuba(lit_scene())
    runs = {k: mcs.render(s, 1024, integrator="direct", strategy=k, seed=i)
            for i, k in enumerate(["emitter", "bsdf", "mis"])}
    for a, b in [("emitter", "bsdf"), ("mis", "bsdf"), ("emitter", "mis")]:
        t = stats.render_ztest(runs[a], runs[b])
        assert t.passed, (a, b, t.message)
    # Power: the same scene with the sphere still at its start differs.
    still = lit_scene()
    del still["ball"]["to_world_end"]
    r = mcs.render(mcs.Scene.from_mitsuba(still), 1024, integrator="direct", seed=9)
    assert not stats.render_ztest(r, runs["mis"]).passed


def test_each_strategy_sees_the_moving_shadow_of_the_sky():
    """The same under a constant sky and no area light, whose BSDF-sampled
    rays need only know whether they leave the scene (the moving sphere
    must stop them at the sample's time, as it stops shadow rays)."""
    def sky_lit(moves=True):
        d = lit_scene()
        del d["light"]
        d["sky"] = {"type": "constant", "radiance": 1.0}
        if not moves:
            del d["ball"]["to_world_end"]
        return mcs.Scene.from_mitsuba(d)

    s = sky_lit()
    runs = {k: mcs.render(s, 1024, integrator="direct", strategy=k, seed=i)
            for i, k in enumerate(["emitter", "bsdf", "mis"])}
    # Path tracing to the third vertex: the last bounce's rays likewise.
    runs["path"] = mcs.render(s, 1024, integrator="path", max_depth=3, seed=4)
    runs["path, emitter"] = mcs.render(s, 1024, integrator="path", max_depth=3,
                                       strategy="emitter", seed=5)
    for a, b in [("emitter", "bsdf"), ("mis", "bsdf"), ("emitter", "mis"),
                 ("path", "path, emitter")]:
        t = stats.render_ztest(runs[a], runs[b])
        assert t.passed, (a, b, t.message)
    r = mcs.render(sky_lit(moves=False), 1024, integrator="direct", seed=9)
    assert not stats.render_ztest(r, runs["mis"]).passed


def test_no_motion_and_a_closed_shutter_are_the_still_scene():
    """Bit for bit: a to_world_end equal to to_world, a shutter of length 0
    (the image at shutter_open), and a camera that does not move."""
    still = mcs.render(mcs.Scene.from_mitsuba(sky_scene(dict(SPHERE, to_world_end=np.eye(4)))),
                       64, integrator="path", max_depth=1, seed=1)
    no_key = {k: v for k, v in SPHERE.items() if k != "to_world_end"}
    base = mcs.render(mcs.Scene.from_mitsuba(sky_scene(no_key)), 64, integrator="path",
                      max_depth=1, seed=1)
    assert np.array_equal(still.image, base.image)
    closed = mcs.render(mcs.Scene.from_mitsuba(sky_scene(SPHERE, shutter_open=0.5,
                                                         shutter_close=0.5)),
                        64, integrator="path", max_depth=1, seed=1)
    assert np.array_equal(closed.image, base.image)
    cam = mcs.render(mcs.Scene.from_mitsuba(sky_scene(no_key, to_world_end=np.eye(4))), 64,
                     integrator="path", max_depth=1, seed=1)
    assert np.array_equal(cam.image, base.image)
    moving = mcs.render(mcs.Scene.from_mitsuba(sky_scene(SPHERE)), 64, integrator="path",
                        max_depth=1, seed=1)
    assert not np.array_equal(moving.image, base.image)


def test_motion_from_a_mitsuba_xml_file(tmp_path):
    path = tmp_path / "motion.xml"
    path.write_text("""<scene version="3.0.0">
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <float name="shutter_open" value="2"/><float name="shutter_close" value="3"/>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="12"/>
      <rfilter type="box"/></film>
  </sensor>
  <shape type="sphere" id="ball">
    <point name="center" value="-1, 0, 5"/><float name="radius" value="0.6"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <transform name="to_world_end"><translate x="2"/></transform>
  </shape>
</scene>""")
    s = mcs.Scene.from_mitsuba(path)
    assert (s.camera.shutter_open, s.camera.shutter_close) == (2.0, 3.0)
    assert np.allclose(s.shapes[0].motion[1], translate(2.0))
    r = mcs.render(s, 1024, integrator="path", max_depth=1, seed=3)
    ztest(r, *oracle(moving_sphere_seen([-1, 0, 5], [2, 0, 0], 0.6)))


def test_bad_motion_is_a_clear_error():
    light = dict(SPHERE, bsdf=BLACK, emitter={"type": "area", "radiance": 1.0})
    cases = [
        (sky_scene(light), r"s0.to_world_end: a moving area light is not supported"),
        (sky_scene(dict(SPHERE, to_world_end=np.diag([1, 0, 1, 1.0]))),
         r"s0.to_world_end: the transform is singular"),
        (sky_scene(dict(SPHERE, to_world_end=np.diag([-1, 1, 1, 1.0]))),
         r"s0.to_world_end: one end of the motion mirrors"),
        (sky_scene(dict(SPHERE, to_world_end=np.eye(3))), r"s0.to_world_end must be a 4x4"),
        (sky_scene(dict(SPHERE, to_world_end="up")), r"s0.to_world_end"),
        (sky_scene(SPHERE, shutter_open=1.0, shutter_close=0.5),
         r"sensor.shutter_close = 0.5: must be finite and >= shutter_open = 1.0"),
        # Mitsuba's default shutter_close is 0, as its shutter_open.
        (sky_scene(SPHERE, shutter_open=0.5, shutter_close=None),
         r"sensor.shutter_close = 0.0: must be finite and >= shutter_open = 0.5"),
        (sky_scene(dict(SPHERE, to_world_end=np.diag([1, 2, 1, 1.0]))),
         r"s0.to_world_end: a sphere takes a uniform scale only"),
        (sky_scene(dict(SPHERE, to_world=np.diag([1, 1, 0, 1.0]))),
         r"s0.to_world_end: the transform at shutter_open \(to_world\) is singular"),
        (sky_scene(SPHERE, to_world_end=np.diag([1, 1, 0, 1.0])),
         r"sensor.to_world_end: the transform is singular"),
    ]
    for d, match in cases:
        with pytest.raises(ValueError, match=match):
            mcs.Scene.from_mitsuba(d)
    with pytest.raises(ValueError, match=r"s0: it moves during the shutter"):
        mcs.Scene.from_mitsuba(sky_scene(SPHERE)).to_mitsuba()
    with pytest.raises(ValueError, match=r"sensor: it moves during the shutter"):
        mcs.Scene.from_mitsuba(sky_scene(to_world_end=translate(1.0))).to_mitsuba()


@pytest.mark.mitsuba
def test_a_closed_shutter_exports_the_still_scene(mi):
    d = mcs.Scene.from_mitsuba(sky_scene(SPHERE, shutter_close=0.0)).to_mitsuba()
    assert "to_world_end" not in d["shape0"] and mi.load_dict(d) is not None
