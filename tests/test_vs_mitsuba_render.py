"""One scene, rendered by mcsample and by Mitsuba 3: statistically the same
image. Each side reports per-pixel means and the variance of each pixel's
mean luminance (Mitsuba through its ``moment`` integrator), so the
difference of the whole-image means and of each 8×8 block's, in standard
errors, must stay within stats.render_ztest's threshold. Each comparison
has the power to find a 2 % bias: the image mean's relative standard error
is below 0.4 %, and the same render made 2 % brighter fails.

Every comparison runs with each of mcsample's samplers (``SAMPLERS``)
against one Mitsuba render with its independent sampler. Under a
stratified sampler a pixel's variance estimate (that of independent
samples) usually overstates its error, so the test stays valid and keeps the
power its relative standard error states."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats
from scenes import (diffuse_sphere_under_sky, ground, icosphere, mesh_scene, phong_spheres,
                    sensor, sphere_on_plane, sunless_sky)

pytestmark = pytest.mark.mitsuba

SPP = 256
SAMPLERS = ("independent", "stratified", "multijitter", "sobol", "ldsampler", "zsobol")

_references: dict = {}


def _scaled(r: mcs.RenderResult, factor: float) -> mcs.RenderResult:
    """The render made ``factor`` times brighter (a planted bias)."""
    return dataclasses.replace(r, image=r.image * factor,
                               luminance_variance=r.luminance_variance * factor ** 2)


def _compare(mi, d, integrator="path", strategy="mis", spp=SPP, seed=1, sampler="independent",
             key=None, variant=None):
    """mcsample's render of ``d`` against Mitsuba's (cached under ``key``;
    in Mitsuba's ``variant``, default the suite's)."""
    scene = mcs.Scene.from_mitsuba(d)
    ours = mcs.render(scene, spp, integrator=integrator, strategy=strategy, seed=seed,
                      progress=False, sampler=sampler)
    key = (key, integrator, spp)
    if key[0] is None or key not in _references:
        _references[key] = mcs.mitsuba.render_reference(scene, spp, seed=seed + 100,
                                                        integrator=integrator, variant=variant)
    ref = _references[key]
    t = stats.render_ztest(ours, ref)
    assert t.relative_se < 0.004, f"too few samples to find a 2 % bias: {t.message}"
    for factor in (0.98, 1.02):
        assert not stats.render_ztest(_scaled(ours, factor), ref).passed, factor
    return t, ours, ref


def _angular_sky():
    return mcs.EnvMap().convert("angular", 256)


def _scene_dicts(tmp_path):
    v, f = icosphere(3)
    path = tmp_path / "blob.ply"
    mcs.io.write_ply(str(path), v * [0.6, 0.45, 0.6] + [0, 0.45, 0], f)
    return {
        "diffuse sphere, default sky": diffuse_sphere_under_sky(),
        "phong spheres n = 1..1000, sky with sun": phong_spheres(),
        "sphere on plane, sky + area light": sphere_on_plane(),
        "triangle mesh from PLY": mesh_scene(path),
        # The camera looks down on the floor: the sky is not seen directly,
        # where the resampling to lat-long for Mitsuba would show as a
        # (deterministic) difference.
        "angular sky": dict(sphere_on_plane(_angular_sky()), floor=ground(size=30.0),
                            sensor=sensor(origin=(0, 4.0, 3.0), target=(0, 0.3, 0))),
    }


@pytest.mark.parametrize("name", ["diffuse sphere, default sky",
                                  "phong spheres n = 1..1000, sky with sun",
                                  "sphere on plane, sky + area light",
                                  "triangle mesh from PLY", "angular sky"])
@pytest.mark.parametrize("integrator", ["direct", "path"])
@pytest.mark.parametrize("sampler", SAMPLERS)
def test_mis_render_equals_mitsubas(mi, tmp_path, name, integrator, sampler):
    # The sun on glossy spheres: rare, bright samples on both sides.
    spp = 16384 if name.startswith("phong spheres") else SPP
    t, ours, ref = _compare(mi, _scene_dicts(tmp_path)[name], integrator=integrator, spp=spp,
                            sampler=sampler, key=name)
    print(f"{name} ({integrator}, {sampler}): {t.message}")
    assert t.passed, t.message
    assert ours.luminance.mean() > 0.05


@pytest.mark.parametrize("strategy", ["bsdf", "emitter", "mis"])
@pytest.mark.parametrize("integrator", ["direct", "path"])
@pytest.mark.parametrize("sampler", SAMPLERS)
def test_every_strategy_converges_to_mitsubas_image(mi, strategy, integrator, sampler):
    """Sphere on a plane under the sunless sky and a large area light (the
    sun makes BSDF sampling heavy-tailed at any affordable spp, which is
    what MIS is for: see the relMSE test)."""
    t, _, _ = _compare(mi, sphere_on_plane(sunless_sky()), integrator=integrator,
                       strategy=strategy, spp=512, sampler=sampler, key="sunless")
    assert t.passed, t.message


def test_a_wrong_envmap_fails_the_test(mi):
    """By construction: mcsample renders with the sky flipped upside down,
    shifted by one texel, or with its emitter-sampling pdf off by 5%
    (emitter sampling only, where that pdf divides every sample: the image
    scales by 1/1.05); each must fail against Mitsuba's render of the true
    sky, while the true sky passes."""
    image = mcs.EnvMap().convert("latlong", (32, 64)).image  # coarse: one texel = 5.6°
    true = mcs.EnvMap(image)
    # A close-up: the sphere fills the frame, so every pixel is lit only
    # through emitter sampling, and the 5% pdf error scales all of them.
    d = dict(diffuse_sphere_under_sky(true),
             sensor=sensor(origin=(0, 0.6, 1.5), target=(0, 0.6, 0), fov=30))
    ref = mcs.mitsuba.render_reference(mcs.Scene.from_mitsuba(d), SPP, seed=7,
                                       integrator="direct")

    def ours(env, strategy="mis", scale=1.0):
        r = mcs.render(mcs.Scene.from_mitsuba(dict(d, sky=env)), SPP, integrator="direct",
                       strategy=strategy, seed=3, progress=False)
        r.image = r.image / scale
        r.luminance_variance = r.luminance_variance / scale ** 2
        return stats.render_ztest(r, ref)

    assert ours(true).passed
    assert ours(true, "emitter").passed
    assert not ours(mcs.EnvMap(image[::-1].copy())).passed
    assert not ours(mcs.EnvMap(np.roll(image, 1, axis=1))).passed
    assert not ours(true, "emitter", scale=1.05).passed


def test_mis_beats_each_strategy_on_glossy_spheres_under_the_sun(mi):
    """relMSE at equal spp against a high-spp MIS reference: MIS is lower
    than BSDF sampling and than emitter sampling (printed)."""
    scene = mcs.Scene.from_mitsuba(phong_spheres())
    reference = mcs.render(scene, 4096, integrator="direct", strategy="mis", seed=99,
                           progress=False).image
    errors = {}
    for strategy in ("bsdf", "emitter", "mis"):
        img = mcs.render(scene, 64, integrator="direct", strategy=strategy, seed=5,
                         progress=False).image
        errors[strategy] = stats.relmse(img, reference)
    print("relMSE at 64 spp:", {k: f"{v:.4g}" for k, v in errors.items()})
    assert errors["mis"] < errors["bsdf"]
    assert errors["mis"] < errors["emitter"]


def test_meshes_export_to_mitsubas_scalar_variant(mi):
    """A scene's meshes (here two rectangles, the floor and the area light,
    and a mesh with vertex normals) go to Mitsuba's scalar variant, the
    fallback where no libLLVM runs, as to the caller's: each buffer holds
    its shape's rows one after the other, and Mitsuba's scalar render of
    the scene agrees with mcsample's. (Before, the buffers went in as
    ``mi.Point3f`` of all the rows, which a scalar variant's single point
    cannot take: a TypeError.)"""
    v, f = icosphere(2)
    blob = {"type": "mesh", "vertices": v * 0.4 + [0.9, 0.4, 0.3], "faces": f, "normals": v,
            "bsdf": {"type": "diffuse", "reflectance": 0.6}}
    d = dict(sphere_on_plane(sunless_sky()), blob=blob, sensor=sensor(width=24, height=18))
    scene = mcs.Scene.from_mitsuba(d)
    expected = []
    for shape in (s for s in scene.shapes if s.kind == "mesh"):
        rows = {"vertex_positions": np.float32(shape.vertices), "faces": np.uint32(shape.faces)}
        if not shape.face_normals and shape.normals is not None:
            rows["vertex_normals"] = np.float32(shape.normals)
        expected.append(rows)
    assert [len(rows) for rows in expected] == [2, 2, 3]
    for variant in ("scalar_rgb", mi.variant()):
        with mcs.mitsuba.variant_set(variant) as m:
            meshes = [x for x in scene.to_mitsuba().values() if isinstance(x, m.Mesh)]
            assert [mesh.has_vertex_normals() for mesh in meshes] == [False, False, True]
            for mesh, rows in zip(meshes, expected):
                params = m.traverse(mesh)
                for key, want in rows.items():
                    assert np.array_equal(np.array(params[key]), want.ravel()), (variant, key)
    t, _, _ = _compare(mi, d, integrator="direct", spp=1024, seed=3, variant="scalar_rgb")
    print("scalar export:", t.message)
    assert t.passed, t.message


def test_reference_renders_leave_the_callers_variant_set(mi):
    """render_reference picks its own variant and sets the caller's back,
    also when Mitsuba raises on the way."""
    scene = mcs.Scene.from_mitsuba(diffuse_sphere_under_sky())
    before = mi.variant()
    try:
        mi.set_variant("scalar_rgb")
        mcs.mitsuba.render_reference(scene, 2, variant=before)
        assert mi.variant() == "scalar_rgb"
        with pytest.raises(ValueError):
            mcs.mitsuba.render_reference(scene, 2, integrator="volpath", variant=before)
        assert mi.variant() == "scalar_rgb"
    finally:
        mi.set_variant(before)
