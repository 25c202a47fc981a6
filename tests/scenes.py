"""Scene dicts shared by the renderer's tests (small films, so the suite
stays fast on two cores)."""

from __future__ import annotations

import numpy as np

import mcsample as mcs

W, H = 48, 36


def sensor(origin=(0, 1.2, 4.5), target=(0, 0.6, 0), fov=35.0, width=W, height=H):
    return {"type": "perspective", "fov": fov,
            "to_world": mcs.look_at(origin, target, [0, 1, 0]),
            "film": {"type": "hdrfilm", "width": width, "height": height,
                     "rfilter": {"type": "box"}}}


def ground(size=4.0, reflectance=0.5):
    """The plane y = 0 facing +y (Mitsuba's rectangle turned about x)."""
    m = np.diag([size, size, size, 1.0]) @ np.array(
        [[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1.0]])
    return {"type": "rectangle", "to_world": m,
            "bsdf": {"type": "diffuse", "reflectance": reflectance}}


def phong(diffuse, specular, exponent):
    return {"type": "mcsample_phong", "diffuse_reflectance": diffuse,
            "specular_reflectance": specular, "exponent": exponent}


def sunless_sky() -> mcs.EnvMap:
    """The packaged sky with the sun clipped: every strategy converges on
    it at modest spp (the sun makes BSDF sampling's estimator heavy-tailed)."""
    image = mcs.EnvMap().image
    return mcs.EnvMap(np.minimum(image, np.percentile(image, 99, axis=(0, 1))))


def diffuse_sphere_under_sky(env=None):
    return {"type": "scene", "sensor": sensor(), "sky": env if env is not None else mcs.EnvMap(),
            "ball": {"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6,
                     "bsdf": {"type": "diffuse", "reflectance": [0.7, 0.6, 0.5]}}}


def phong_spheres(exponents=(1, 10, 100, 1000)):
    d = {"type": "scene", "sensor": sensor(origin=(0, 1.5, 6.0), target=(0, 0.5, 0), fov=40,
                                            width=64, height=24),
         "sky": mcs.EnvMap()}
    for i, n in enumerate(exponents):
        x = 1.3 * (i - (len(exponents) - 1) / 2)
        d[f"ball{i}"] = {"type": "sphere", "center": [x, 0.5, 0], "radius": 0.5,
                         "bsdf": phong(0.2, 0.7, n)}
    return d


def sphere_on_plane(env=None):
    light = np.array([[0.4, 0, 0, 1.0], [0, 0, 1, 2.0], [0, -0.4, 0, 0.8], [0, 0, 0, 1.0]])
    return {"type": "scene", "sensor": sensor(), "sky": env if env is not None else mcs.EnvMap(),
            "ball": {"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6,
                     "bsdf": phong(0.4, 0.3, 20)},
            "floor": ground(),
            # Facing down (-y): Mitsuba's rectangle faces +z, turned about x.
            "light": {"type": "rectangle", "to_world": light,
                      "emitter": {"type": "area", "radiance": [12.0, 11.0, 9.0]}}}


def mesh_scene(ply_path):
    return {"type": "scene", "sensor": sensor(), "sky": mcs.EnvMap(),
            "bunny": {"type": "ply", "filename": str(ply_path),
                      "bsdf": {"type": "twosided", "bsdf": phong(0.5, 0.3, 30)}},
            "floor": ground()}


def icosphere(subdivisions=2):
    """A unit icosphere (vertices, faces), counter-clockwise from outside."""
    t = (1 + 5 ** 0.5) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    verts = [np.array(p, dtype=np.float64) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        cache: dict = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]

        f = [g for a, b, c in f for g in
             ([a, mid(a, b), mid(c, a)], [b, mid(b, c), mid(a, b)],
              [c, mid(c, a), mid(b, c)], [mid(a, b), mid(b, c), mid(c, a)])]
    return np.array(verts), np.array(f, dtype=np.int64)
