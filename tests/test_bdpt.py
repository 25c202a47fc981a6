"""Bidirectional path tracing (``integrator="bdpt"``).

Every strategy (s, t) estimates the light of the paths of its length on
its own; MIS weights them into one image. So:

- against mcsample's path tracer (which shares only the scene): area lights
  near, far and grazing, a sphere light, the sky seen directly and through
  light subpaths, Phong lobes, a glossy sphere in a mirror-like Phong
  floor, a constant and a cube-mapped environment, a thin lens, a moving
  sphere and a moving camera, a two-sided
  mesh with vertex normals, and a closed room lit through its ceiling (also with unbounded paths and
  Russian roulette), with the power and the balance heuristic;
- against Mitsuba 3's ``path``: the cross-renderer scenes of
  test_vs_mitsuba_render, the room and the mirror floor (and light tracing
  on four of them: not on glossy lobes under the sun, a mirror floor, or a
  30 × 30 floor of which the camera sees a corner, where light paths reach
  the pixels too rarely to converge in a test);
- each strategy's unweighted image mean against the best-sampled one of
  its path length (each is an unbiased estimate of the same light: a
  strategy whose own estimate is wrong stands out even where its MIS
  weight is small), and the weighted images adding up to the render.

``stats.render_ztest`` compares whole-image means and 8×8 blocks in
standard errors; the sample counts keep the image mean's relative standard
error under 0.6 % (1 % for the sun on Phong spheres), so a bias of 3 %
(5 %) lies beyond the threshold.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ndtri

import mcsample as mcs
from mcsample import stats
from scenes import (area_lit_floor, diffuse_sphere_under_sky, ground, icosphere, lit_room,
                    mesh_scene, phong, phong_spheres, sensor, sphere_on_plane, sunless_sky)
from test_ptracer import SCENES as LIGHT_TRACING_SCENES, INTEGRATOR

ALPHA = 1e-4


def mirror_floor() -> dict:
    """A glossy Phong sphere (n = 60) on a mirror-like Phong floor (n =
    3000), lit by a small sphere light and the sunless sky, the camera low
    so that it sees the sphere's reflection."""
    return {"type": "scene", "sensor": sensor(origin=(0, 1.0, 4.5), target=(0, 0.3, 0)),
            "sky": sunless_sky(),
            "ball": {"type": "sphere", "center": [0, 0.6, 0], "radius": 0.5,
                     "bsdf": phong(0.1, 0.6, 60)},
            "floor": dict(ground(), bsdf=phong(0.05, 0.9, 3000)),
            "light": {"type": "sphere", "center": [1.2, 1.8, 0.5], "radius": 0.15,
                      "emitter": {"type": "area", "radiance": 40.0}}}


def _blob(tmp_path) -> dict:
    v, f = icosphere(3)
    path = tmp_path / "blob.ply"
    mcs.io.write_ply(str(path), v * [0.6, 0.45, 0.6] + [0, 0.45, 0], f)
    return mesh_scene(path)


#: name → (scene dict maker, bdpt spp, path spp, integrator keys).
SCENES = {name: (make, 512, 1024, {}) if name == "grazing rectangle"
          else (make, 64, path_spp, INTEGRATOR.get(name, {}))
          for name, (make, _, path_spp) in LIGHT_TRACING_SCENES.items()}
SCENES["mirror floor"] = (lambda tmp: mirror_floor(), 64, 256, {})
SCENES["sphere on plane under a constant sky"] = (
    lambda tmp: sphere_on_plane({"type": "constant", "radiance": [0.8, 0.9, 1.0]}), 64, 256, {})
SCENES["two-sided mesh with vertex normals"] = (_blob, 64, 256, {})


def _scene(name: str, tmp_path, **keys) -> tuple[mcs.Scene, int, int]:
    make, spp, path_spp, integrator = SCENES[name]
    d = make() if name in LIGHT_TRACING_SCENES else make(tmp_path)
    d["integrator"] = {"type": "path", "max_depth": 6, **integrator, **keys}
    return mcs.Scene.from_mitsuba(d), spp, path_spp


@pytest.mark.parametrize("name", list(SCENES))
def test_bdpt_matches_path_tracing(name, tmp_path):
    scene, spp, path_spp = _scene(name, tmp_path)
    ours = mcs.render(scene, spp, seed=1, progress=False, integrator="bdpt")
    path = mcs.render(scene, path_spp, seed=2, progress=False, integrator="path")
    t = stats.render_ztest(ours, path, alpha=ALPHA)
    print(f"{name}: {t.message}")
    assert t.passed, t.message
    assert t.relative_se < 0.006, "too few samples to find a 3 % bias"


@pytest.mark.parametrize("name", ["sphere on plane, sky and light", "room lit through the ceiling",
                                  "mirror floor"])
def test_balance_heuristic_too(name, tmp_path):
    scene, spp, path_spp = _scene(name, tmp_path)
    ours = mcs.render(scene, spp, seed=3, progress=False, integrator="bdpt", heuristic="balance")
    path = mcs.render(scene, path_spp, seed=4, progress=False, integrator="path")
    t = stats.render_ztest(ours, path, alpha=ALPHA)
    assert t.passed, t.message


def test_hidden_emitters_as_light_tracing_hides_them(tmp_path):
    """With hide_emitters, bidirectional path tracing leaves out the light
    the camera receives straight from a light, as light tracing (Mitsuba's
    ptracer) does: area lights still block and reflect (the path tracer
    instead sees through them)."""
    # A sphere light, seen by the camera from its emitting side.
    scene, _, _ = _scene("near sphere", tmp_path, hide_emitters=True)
    ours = mcs.render(scene, 128, seed=6, progress=False, integrator="bdpt")
    light = mcs.render(scene, 512, seed=7, progress=False, integrator="ptracer")
    t = stats.render_ztest(ours, light, alpha=ALPHA)
    assert t.passed, t.message
    assert t.relative_se < 0.006


def test_gaussian_filter_splats_as_light_tracing(tmp_path):
    """Under the Gaussian filter, camera samples are splatted with the
    light connections' normalised weights: the image is light tracing's,
    compared with region variances from independent runs."""
    from test_ptracer import runs

    d = sphere_on_plane(sunless_sky())
    d["sensor"]["film"] = dict(d["sensor"]["film"], rfilter={"type": "gaussian"})
    d["integrator"] = {"type": "path", "max_depth": 6}
    scene = mcs.Scene.from_mitsuba(d)
    ours = runs(scene, 256, seed=8, integrator="bdpt")
    light = runs(scene, 2048, seed=9, integrator="ptracer")
    t = stats.render_ztest(ours, light, alpha=ALPHA)
    print(t.message)
    assert t.passed, t.message
    assert t.relative_se < 0.01


def _mean_and_se(luminance: np.ndarray, variance: np.ndarray) -> tuple[float, float]:
    """The image's mean luminance and its standard error."""
    return float(luminance.mean()), float(np.sqrt(variance.sum()) / variance.size)


@pytest.mark.parametrize("name", ["room lit through the ceiling", "sphere on plane, sky and light",
                                  "near sphere"])
def test_every_strategy_alone_estimates_the_light_of_its_path_length(name, tmp_path):
    """Per path length, each strategy's unweighted image mean against the
    best strategy's (least noise), in standard errors, for the strategies
    whose mean has a relative standard error under 10 % (the others find
    their paths too rarely for a normal z: a few hits, heavy tails); and
    the weighted images add up to the render."""
    scene, _, _ = _scene(name, tmp_path, max_depth=4)
    r = mcs.render(scene, 1024, seed=5, progress=False, integrator="bdpt", strategies=True)
    assert sorted(r.strategies) == sorted(mcs._core.render.bdpt_strategies(4))
    total = sum(v.weighted for v in r.strategies.values())
    np.testing.assert_allclose(total, r.image, rtol=1e-4, atol=1e-6)
    luminance = {st: np.asarray(v.unweighted, np.float64) @ [0.2126, 0.7152, 0.0722]
                 for st, v in r.strategies.items()}
    estimates = {st: _mean_and_se(luminance[st], v.unweighted_variance)
                 for st, v in r.strategies.items()}
    tested = []
    for depth in range(2, 5):
        row = [st for st in r.strategies if sum(st) - 1 == depth]
        best = min(row, key=lambda st: estimates[st][1])
        for st in row:
            mean, se = estimates[st]
            if st == best or not se < 0.1 * abs(mean):
                continue
            z = (mean - estimates[best][0]) / np.hypot(se, estimates[best][1])
            print(f"depth {depth} {st} vs {best}: {mean:.5g} ± {se:.2g} vs "
                  f"{estimates[best][0]:.5g} ± {estimates[best][1]:.2g}: z = {z:.2f}")
            tested.append((st, z))
    # Šidák: alpha shared by the z-tests.
    threshold = -ndtri((1 - (1 - ALPHA) ** (1 / len(tested))) / 2)
    assert len(tested) >= 4
    assert all(abs(z) < threshold for _, z in tested), tested


def test_strategy_images_need_bdpt_and_a_finite_depth():
    scene = mcs.Scene.from_mitsuba(area_lit_floor("rectangle", "near", width=8, height=6))
    with pytest.raises(ValueError, match="bdpt"):
        mcs.render(scene, 2, progress=False, strategies=True)
    with pytest.raises(ValueError, match="max_depth"):
        mcs.render(scene, 2, progress=False, integrator="bdpt", strategies=True, max_depth=-1)
    with pytest.raises(ValueError, match="first_sample"):
        mcs.render(scene, 2, progress=False, integrator="bdpt", strategies=True, max_depth=3,
                   first_sample=0)


def test_strategies_plot(tmp_path):
    pytest.importorskip("matplotlib")
    scene = mcs.Scene.from_mitsuba(dict(lit_room(width=16, height=12),
                                        integrator={"type": "path", "max_depth": 3}))
    r = mcs.render(scene, 4, progress=False, integrator="bdpt", strategies=True)
    fig = mcs.plot.strategies(r, weighted=False)
    titled = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert len(titled) == len(r.strategies) == 1 + 3 + 4
    fig.savefig(tmp_path / "strategies.png")
    with pytest.raises(ValueError, match="strategies"):
        mcs.plot.strategies(mcs.render(scene, 1, progress=False))


def _cross_renderer(tmp_path) -> dict:
    from test_vs_mitsuba_render import _scene_dicts

    d = _scene_dicts(tmp_path)
    d["room lit through the ceiling"] = dict(
        lit_room(), integrator={"type": "path", "max_depth": 6, "hide_emitters": False})
    d["mirror floor"] = mirror_floor()
    return d


#: Mitsuba's references, shared by the bidirectional and light tracers.
_references: dict = {}


@pytest.mark.mitsuba
@pytest.mark.parametrize("name, integrator, spp", [
    ("diffuse sphere, default sky", "bdpt", 64),
    ("phong spheres n = 1..1000, sky with sun", "bdpt", 2048),
    ("sphere on plane, sky + area light", "bdpt", 64),
    ("triangle mesh from PLY", "bdpt", 64),
    ("angular sky", "bdpt", 64),
    ("room lit through the ceiling", "bdpt", 64),
    ("mirror floor", "bdpt", 64),
    # Light tracing, where it finds the light the camera sees often enough.
    ("diffuse sphere, default sky", "ptracer", 1024),
    ("sphere on plane, sky + area light", "ptracer", 2048),
    ("triangle mesh from PLY", "ptracer", 2048),
    ("room lit through the ceiling", "ptracer", 512),
])
def test_bidirectional_and_light_tracing_match_mitsubas_path_tracer(mi, tmp_path, name,
                                                                     integrator, spp):
    d = _cross_renderer(tmp_path)[name]
    d.setdefault("integrator", {"type": "path", "max_depth": 6})
    scene = mcs.Scene.from_mitsuba(d)
    ref_spp = 16384 if name.startswith("phong") else 1024
    if name not in _references:
        _references[name] = mcs.mitsuba.render_reference(scene, ref_spp, seed=11,
                                                          integrator="path")
    ref = _references[name]
    ours = mcs.render(scene, spp, seed=12, progress=False, integrator=integrator)
    t = stats.render_ztest(ours, ref, alpha=ALPHA)
    print(f"{name}: {t.message}")
    assert t.passed, t.message
    assert t.relative_se < (0.01 if name.startswith("phong") else 0.006)
