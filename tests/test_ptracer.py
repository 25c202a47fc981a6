"""Light tracing (``integrator="ptracer"``, as Mitsuba's ``ptracer``).

The light tracer and the path tracer share nothing but the scene: paths
start on the lights and are connected to the camera, splatted onto the
film. So each scene below (area lights near, far and grazing, a sphere
light, the environment (lat-long and cube-mapped) seen directly and
through light paths that enter by the scene's bounding disk, Phong lobes,
a thin lens, a moving sphere and a moving camera, and a closed room lit
through its ceiling, also with unbounded paths and Russian
roulette) is rendered by both and compared by
``stats.render_ztest`` (the whole image's mean and 8×8 blocks, in standard
errors): the sample counts keep the image mean's relative standard error
under 0.6 %, so a bias of 3 % lies beyond the test's threshold. Against
Mitsuba 3's own ``ptracer``: the same, with the box and the Gaussian
filter (whose normalised splats are Mitsuba's). The variance of a pixel
comes from its value on every light path: its calibration is tested over
independent seeds. Chunks of samples merge to the bits of one render, at
any thread count (these two also for bidirectional path tracing, which
shares the light tracer's film).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats
from scenes import area_lit_floor, lit_room, phong, sensor, skip_scalar, sphere_on_plane, \
    sunless_sky

#: Significance of each comparison, shared by the file's tests.
ALPHA = 1e-4


def _sky_lit_spheres() -> dict:
    """Phong spheres (exponents 1, 10, 100) on a floor under the sunless
    sky, which is seen directly above them."""
    d = {"type": "scene", "sensor": sensor(origin=(0, 1.5, 6.0), target=(0, 0.8, 0), fov=40,
                                           width=40, height=20),
         "sky": sunless_sky(),
         "floor": {"type": "rectangle", "to_world": np.diag([4.0, 4.0, 4.0, 1.0])
                   @ np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1.0]]),
                   "bsdf": {"type": "diffuse", "reflectance": 0.5}}}
    for i, n in enumerate((1, 10, 100)):
        d[f"ball{i}"] = {"type": "sphere", "center": [1.3 * (i - 1), 0.5, 0], "radius": 0.5,
                         "bsdf": phong(0.3, 0.5, n)}
    return d


def _thin_lens(d: dict) -> dict:
    d = dict(d)
    d["sensor"] = dict(d["sensor"], type="thinlens", aperture_radius=0.08, focus_distance=4.0)
    return d


def _moving_camera(d: dict) -> dict:
    d = dict(d)
    end = np.asarray(d["sensor"]["to_world"], dtype=float).copy()
    end[:3, 3] += [0.4, 0.1, 0.0]
    d["sensor"] = dict(d["sensor"], shutter_open=0.0, shutter_close=1.0, to_world_end=end)
    return d


def _cube_sky(d: dict) -> dict:
    return dict(d, sky=mcs.EnvMap(np.asarray(sunless_sky().image)).convert("cube", 48))


def _moving(d: dict) -> dict:
    d = dict(d)
    d["sensor"] = dict(d["sensor"], shutter_open=0.0, shutter_close=1.0)
    ball = dict(d["ball"])
    ball["to_world_end"] = np.array([[1, 0, 0, 0.5], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    d["ball"] = ball
    return d


#: name → (scene dict, samples per pixel of the light tracer, of the path tracer).
SCENES = {
    "near rectangle": (lambda: area_lit_floor("rectangle", "near"), 256, 256),
    "far rectangle": (lambda: area_lit_floor("rectangle", "far"), 512, 64),
    "grazing rectangle": (lambda: area_lit_floor("rectangle", "grazing"), 256, 256),
    "near sphere": (lambda: area_lit_floor("sphere", "near"), 256, 256),
    "sky-lit Phong spheres": (_sky_lit_spheres, 4096, 1024),
    "sphere on plane, sky and light": (lambda: sphere_on_plane(sunless_sky()), 1024, 256),
    "thin lens": (lambda: _thin_lens(sphere_on_plane(sunless_sky())), 1024, 256),
    "motion blur": (lambda: _moving(sphere_on_plane(sunless_sky())), 1024, 256),
    "moving camera": (lambda: _moving_camera(sphere_on_plane(sunless_sky())), 1024, 256),
    "cube-mapped sky": (lambda: _cube_sky(sphere_on_plane()), 1024, 256),
    "room lit through the ceiling": (lambda: lit_room(), 512, 1024),
    "room, unbounded paths, roulette from depth 2": (lambda: lit_room(), 512, 1024),
}

#: Integrator keys other than max_depth 6.
INTEGRATOR = {"room, unbounded paths, roulette from depth 2": {"max_depth": -1, "rr_depth": 2}}


def _scene(name: str, integrator: str = "ptracer") -> tuple[mcs.Scene, int, int]:
    make, spp, path_spp = SCENES[name]
    d = make()
    d["integrator"] = {"type": integrator, "max_depth": 6, **INTEGRATOR.get(name, {})}
    return mcs.Scene.from_mitsuba(d), spp, path_spp


def runs(scene: mcs.Scene, spp: int, seed: int, count: int = 16, **kw) -> mcs.RenderResult:
    """``count`` independent renders of ``spp / count`` samples as one
    result with ``.runs`` (whose spread gives region variances, the
    pixels' covariances included: stats.render_ztest)."""
    results = [mcs.render(scene, spp // count, seed=seed * 1000 + k, progress=False, **kw)
               for k in range(count)]
    y = np.stack([r.luminance for r in results])
    image = np.mean([r.image for r in results], axis=0)
    return mcs.RenderResult(image, None, (y.var(axis=0, ddof=1) / count).astype(np.float32),
                            spp, sum(r.seconds for r in results), runs=y.astype(np.float32))


@pytest.mark.parametrize("name", list(SCENES))
def test_light_tracing_matches_path_tracing(name):
    scene, spp, path_spp = _scene(name)
    light = mcs.render(scene, spp, seed=1, progress=False)
    path = mcs.render(scene, path_spp, seed=2, progress=False, integrator="path")
    t = stats.render_ztest(light, path, alpha=ALPHA)
    print(f"{name}: {t.message}")
    assert t.passed, t.message
    assert t.relative_se < 0.006, "too few samples to find a 3 % bias"


@pytest.mark.parametrize("max_depth", [1, 2, 3])
def test_path_lengths_are_mitsubas(max_depth):
    """max_depth 1: the lights seen directly; 2: direct light; 3: one
    bounce more, each equal to the path tracer's of the same max_depth."""
    scene, spp, path_spp = _scene("sphere on plane, sky and light")
    light = mcs.render(scene, spp, seed=3, progress=False, max_depth=max_depth)
    path = mcs.render(scene, path_spp, seed=4, progress=False, integrator="path",
                      max_depth=max_depth)
    t = stats.render_ztest(light, path, alpha=ALPHA)
    assert t.passed, t.message


@pytest.mark.parametrize("integrator", ["ptracer", "bdpt"])
def test_variance_is_that_of_the_pixel_means_over_seeds(integrator):
    """Each pixel's reported variance (light tracing: from its value on
    every light path; bidirectional: from its per-sample totals) against
    the spread of its mean over 24 independent renders: their ratio, pooled
    over the pixels the light reaches, lies near 1."""
    d = area_lit_floor("rectangle", "near", width=16, height=12)
    scene = mcs.Scene.from_mitsuba(d)
    runs = [mcs.render(scene, 16, seed=100 + k, progress=False, integrator=integrator)
            for k in range(24)]
    y = np.stack([r.luminance for r in runs])
    reported = np.mean([r.luminance_variance for r in runs], axis=0)
    lit = reported > 0
    ratio = y.var(axis=0, ddof=1)[lit].sum() / reported[lit].sum()
    print(f"empirical / reported variance: {ratio:.3f} over {lit.sum()} pixels")
    assert 0.8 < ratio < 1.25


@pytest.mark.parametrize("integrator", ["ptracer", "bdpt"])
def test_chunks_merge_to_one_render_at_any_thread_count(integrator):
    scene, _, _ = _scene("sphere on plane, sky and light")
    render = functools.partial(mcs.render, scene, seed=5, progress=False, integrator=integrator)
    mcs.set_num_threads(1)
    whole = render(6)
    mcs.set_num_threads(2)
    again = render(6)
    merged = mcs.RenderResult.merge([render(n, first_sample=k)
                                     for k, n in [(0, 1), (1, 3), (4, 2)]])
    for r in (again, merged):
        np.testing.assert_array_equal(r.image, whole.image)
        np.testing.assert_array_equal(r.variance, whole.variance)
        np.testing.assert_array_equal(r.luminance_variance, whole.luminance_variance)
    assert merged.spp == 6
    # Another seed gives another image.
    assert not np.array_equal(render(6, seed=6).image, whole.image)


def test_a_scene_dict_names_the_light_tracer():
    d = area_lit_floor("rectangle", "near", width=8, height=6)
    d["integrator"] = {"type": "ptracer", "max_depth": 3, "samples_per_pass": 4}
    scene = mcs.Scene.from_mitsuba(d)
    assert scene.integrator_settings()["integrator"] == "ptracer"
    r = mcs.render(scene, 2, progress=False)
    assert r.image.shape == (6, 8, 3) and r.image.max() > 0
    with pytest.raises(ValueError, match="integrator"):
        mcs.render(scene, 2, progress=False, integrator="bidir")


@pytest.mark.mitsuba
@pytest.mark.parametrize("name, rfilter", [
    ("near rectangle", "box"),
    ("grazing rectangle", "box"),
    ("sphere on plane, sky and light", "gaussian"),
    ("room lit through the ceiling", "box"),
])
def test_light_tracing_matches_mitsubas_ptracer(mi, name, rfilter):
    make, spp, _ = SCENES[name]
    d = make()
    d["integrator"] = {"type": "ptracer", "max_depth": 6}
    if rfilter == "gaussian":
        skip_scalar(mi)
        d["sensor"]["film"] = dict(d["sensor"]["film"], rfilter={"type": "gaussian"})
    scene = mcs.Scene.from_mitsuba(d)
    ref = mcs.mitsuba.render_reference(scene, spp, seed=7)
    # Under the Gaussian filter a splat spreads over neighbouring pixels:
    # region variances from independent runs, as for Mitsuba's side.
    ours = runs(scene, spp, seed=8) if rfilter == "gaussian" else \
        mcs.render(scene, spp, seed=8, progress=False)
    t = stats.render_ztest(ours, ref, alpha=ALPHA)
    print(f"{name} ({rfilter}): {t.message}")
    assert t.passed, t.message
    assert t.relative_se < 0.01
