"""Emitter sampling, as the renderer's next-event estimation draws it
(``Scene.sample_emitter``), against its own density (``Scene.emitter_pdf``)
and against solid angles computed independently of both:

- E[1/pdf] over the samples from a point is the solid angle of the light's
  front side seen from there (the samples that carry no light count 0); the
  oracle sums exact triangle solid angles (Van Oosterom and Strackee), or
  integrates cos θ / r² over a disk or a sphere's visible cap by Gauss
  quadrature;
- a chi-square test of the sampled directions against ``emitter_pdf``, in a
  cone around the light, with expected counts by jittered (unbiased)
  integration, since the density jumps at the light's edge.

Every shape of ``area`` light (rectangle, disk, sphere, cube, triangle
mesh, under non-uniform scale and rotation), from points near it, far from
it and at grazing angles; the environment map and ``constant`` emitters.
"""

from __future__ import annotations

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats
from scenes import LIGHT_SHAPES, area_light, sensor

#: Receiver points around the light of ``area_light(shape, "near")``
#: (centre (0, 0.4, 0), half-size 0.25; flat lights face down, -y):
#: below it, far away, and almost in the plane of a flat light.
RECEIVERS = {
    "near": (0.05, 0.0, 0.1),
    "far": (2.0, -3.0, 1.5),
    "grazing": (1.2, 0.37, 0.4),
    # Two more at random (fixed seed) within a few sizes of the light.
    **{f"random {k}": tuple(np.random.default_rng(31 + k).uniform(-1.0, 1.0, 3) * [1.5, 1.0, 1.5]
                             + [0.0, 0.4, 0.0] + [0.0, 0.7 * (-1) ** k, 0.0])
       for k in range(2)},
}

N = 400_000


def light_scene(*lights, env=None) -> mcs.Scene:
    d = {"type": "scene", "sensor": sensor()}
    for i, light in enumerate(lights):
        d[f"light{i}"] = light
    if env is not None:
        d["env"] = env
    return mcs.Scene.from_mitsuba(d)


def triangle_solid_angles(x, v0, v1, v2):
    """Solid angles of triangles seen from x (Van Oosterom and Strackee
    1983): tan(Ω/2) = |a·(b×c)| / (abc + (a·b)c + (a·c)b + (b·c)a)."""
    a, b, c = v0 - x, v1 - x, v2 - x
    la, lb, lc = (np.linalg.norm(t, axis=-1) for t in (a, b, c))
    num = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb
           + np.einsum("ij,ij->i", b, c) * la)
    return 2.0 * np.arctan2(num, den)


def front_solid_angle(scene: mcs.Scene, x) -> float:
    """The solid angle of the light's front side seen from x (each front
    facing part counted once, as the sampler ignores self-occlusion)."""
    x = np.asarray(x, dtype=np.float64)
    (shape,) = scene.shapes
    if shape.kind == "sphere":
        c, r = np.asarray(shape.center), shape.radius
        dist = np.linalg.norm(x - c)
        # The visible cap, θ from the axis toward x: cos θ > r / dist.
        t, w = np.polynomial.legendre.leggauss(64)
        cos_t = r / dist + (1 - r / dist) * (t + 1) / 2
        p_minus_x2 = dist ** 2 + r ** 2 - 2 * dist * r * cos_t
        cos_light = (dist * cos_t - r) / np.sqrt(p_minus_x2)
        return float(2 * np.pi * r * r * np.sum(w * cos_light / p_minus_x2)
                     * (1 - r / dist) / 2)
    if shape.kind == "disk":
        m = shape.to_world
        normal = np.linalg.inv(m[:3, :3]).T @ [0, 0, 1]
        normal /= np.linalg.norm(normal)
        if np.dot(x - m[:3, 3], normal) <= 0:
            return 0.0
        t, w = np.polynomial.legendre.leggauss(96)
        rr, wr = (t + 1) / 2, w / 2
        phi = np.linspace(0, 2 * np.pi, 512, endpoint=False)
        local = np.stack([np.outer(rr, np.cos(phi)), np.outer(rr, np.sin(phi)),
                          np.zeros((rr.size, phi.size))], axis=-1)
        p = local @ m[:3, :3].T + m[:3, 3]
        to_x = x - p
        d2 = np.sum(to_x * to_x, axis=-1)
        cos_light = to_x @ normal / np.sqrt(d2)
        jac = np.linalg.norm(np.cross(m[:3, 0], m[:3, 1]))
        integrand = cos_light / d2 * rr[:, None] * jac
        return float(np.sum(wr[:, None] * integrand) * (2 * np.pi / phi.size))
    v, f = shape.vertices, shape.faces
    v0, v1, v2 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    front = np.einsum("ij,ij->i", np.cross(v1 - v0, v2 - v0), x - v0) > 0
    return float(triangle_solid_angles(x, v0[front], v1[front], v2[front]).sum())


def light_cone(scene: mcs.Scene, x):
    """A frame whose +z points from x to the light's centre, and the cosine
    of a cone around it that holds the whole light."""
    (shape,) = scene.shapes
    x = np.asarray(x, dtype=np.float64)
    if shape.kind == "sphere":
        c, radius = np.asarray(shape.center), shape.radius
    elif shape.kind == "disk":
        m = shape.to_world
        c = m[:3, 3]
        radius = np.linalg.norm(m[:3, 0]) + np.linalg.norm(m[:3, 1])
    else:
        c = shape.vertices.mean(axis=0)
        radius = np.linalg.norm(shape.vertices - c, axis=1).max()
    dist = np.linalg.norm(c - x)
    sin_max = min(1.02 * radius / dist, 1.0)
    cos_max = np.sqrt(1 - sin_max ** 2) - 1e-3 if sin_max < 1 else -1.0
    return mcs.Frame((c - x) / dist), max(cos_max, -1.0)


CASES = [(shape, where) for shape in LIGHT_SHAPES for where in RECEIVERS]


@pytest.mark.parametrize("shape,where", CASES)
def test_mean_inverse_pdf_is_the_solid_angle(shape, where):
    scene = light_scene(area_light(shape, "near"))
    x = RECEIVERS[where]
    s = scene.sample_emitter(x, mcs.uniform(N, 3, seed=11))
    inv = np.where(s.pdf > 0, 1.0 / np.where(s.pdf > 0, s.pdf, 1.0), 0.0)
    mean, se = inv.mean(), inv.std() / np.sqrt(N)
    omega = front_solid_angle(scene, x)
    print(f"{shape} from {where}: E[1/pdf] = {mean:.6g} ± {se:.2g}, solid angle {omega:.6g}")
    assert omega > 1e-3
    assert abs(mean - omega) < 5 * se + 1e-4 * omega
    # Radiance arrives only from the samples that carry it.
    valid = s.pdf > 0
    assert np.all(s.radiance[valid] > 0) and np.all(s.radiance[~valid] == 0)
    np.testing.assert_allclose(np.linalg.norm(s.direction[valid], axis=1), 1, atol=1e-6)


@pytest.mark.parametrize("shape,where", CASES)
def test_sampled_directions_follow_the_pdf(shape, where):
    scene = light_scene(area_light(shape, "near"))
    x = np.asarray(RECEIVERS[where])
    frame, cos_max = light_cone(scene, x)

    def sample(u):
        s = scene.sample_emitter(x, u)
        return frame.to_local(s.direction[s.pdf > 0])

    def pdf(d):
        return scene.emitter_pdf(x, frame.to_world(d))

    t = stats.chi2_test(sample, pdf, stats.ConeDomain(cos_max), n=N, sample_dim=3, res=41,
                        ires=4, integration="jittered", seed=5, alpha=1e-3,
                        test_count=len(CASES))
    assert t.passed, t.message
    # The sampler's density is the one MIS weighs its BSDF-sampled hits by.
    s = scene.sample_emitter(x, mcs.uniform(1000, 3, seed=3))
    valid = s.pdf > 0
    np.testing.assert_allclose(scene.emitter_pdf(x, s.direction[valid]), s.pdf[valid],
                               rtol=2e-3)


def test_the_choice_among_lights_is_by_power():
    """Two area lights and the sky: every light's samples carry its own
    density times the probability of its choice, so the mixture passes the
    chi-square test on the whole sphere."""
    rect = area_light("rectangle", "near", radiance=3.0)
    ball = dict(area_light("sphere", "near"), center=[0.8, 0.4, -0.3], radius=0.2)
    scene = light_scene(rect, ball, env=mcs.EnvMap())
    x = np.array([0.2, 0.0, 0.1])

    def sample(u):
        s = scene.sample_emitter(x, u)
        return s.direction[s.pdf > 0]

    t = stats.chi2_test(sample, lambda d: scene.emitter_pdf(x, d), "sphere", n=N,
                        sample_dim=3, res=61, ires=4, integration="jittered", seed=2,
                        alpha=1e-3)
    assert t.passed, t.message


@pytest.mark.parametrize("kind", ["envmap", "constant"])
def test_environment_emitters(kind):
    env = mcs.EnvMap() if kind == "envmap" else {"type": "constant", "radiance": 0.7}
    scene = light_scene(env=env)
    x = np.zeros(3)
    s = scene.sample_emitter(x, mcs.uniform(N, 3, seed=4))
    assert np.all(s.pdf > 0) and np.all(np.isinf(s.distance))
    # The sky has light in every direction: E[1/pdf] = 4π.
    inv = 1.0 / s.pdf
    assert abs(inv.mean() - 4 * np.pi) < 5 * inv.std() / np.sqrt(N) + 1e-6
    domain = stats.EnvMapDomain(scene.environment[1]) if kind == "envmap" else "sphere"
    res = domain.cells if kind == "envmap" else 51
    t = stats.chi2_test(lambda u: scene.sample_emitter(x, u).direction,
                        lambda d: scene.emitter_pdf(x, d), domain, n=N, sample_dim=3, res=res,
                        alpha=1e-3, test_count=2)
    assert t.passed, t.message
    radiance = (scene.environment[1].eval(s.direction[:100]) if kind == "envmap"
                else np.full((100, 3), 0.7))
    np.testing.assert_allclose(s.radiance[:100], radiance, rtol=1e-5)
