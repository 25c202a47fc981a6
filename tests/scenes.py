"""Scene dicts shared by the renderer's tests (small films, so the suite
stays fast on two cores)."""

from __future__ import annotations

import numpy as np
import pytest

import mcsample as mcs
from mcsample.scene import icosphere  # noqa: F401 (the tests import it from here)

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


def transform(translate=(0.0, 0.0, 0.0), rotate=(), scale=(1.0, 1.0, 1.0)) -> np.ndarray:
    """The 4×4 matrix T·R·S: scale first, then the rotations ``rotate``
    ((axis, degrees) pairs, applied in order), then the translation."""
    m = np.diag([*map(float, scale), 1.0])
    for axis, degrees in rotate:
        c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
        i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
        r = np.eye(4)
        r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
        m = r @ m
    m[:3, 3] = translate
    return m


#: Where an area light sits over the floor y = 0: its centre, its size (the
#: largest half-extent), the turn that faces a flat light (Mitsuba's
#: rectangle and disk face +z) toward the floor, its radiance, and the
#: camera (origin, target) that frames the floor it lights:
#: - near: as high as it is wide;
#: - far: 15 sizes up;
#: - grazing: low beside the lit part of the floor, facing along it (10°
#:   down), so that light reaches the floor at grazing angles.
LIGHT_PLACES = {
    "near": ((0.0, 0.4, 0.0), 0.25, [("x", 90.0)], 4.0, ((0.4, 1.3, 1.1), (0.0, 0.0, 0.0))),
    "far": ((0.0, 3.0, 0.0), 0.2, [("x", 90.0)], 60.0, ((0.3, 2.4, 2.0), (0.0, 0.0, 0.0))),
    "grazing": ((-1.4, 0.3, 0.0), 0.2, [("y", 90.0), ("z", -10.0)], 12.0,
                ((-0.1, 1.6, 1.4), (-0.7, 0.0, 0.0))),
}

LIGHT_SHAPES = ("rectangle", "disk", "sphere", "cube", "mesh")


def area_light(shape: str, place: str, radiance: float = 1.0) -> dict:
    """An area light of ``shape`` at ``place`` (:data:`LIGHT_PLACES`),
    under a non-uniform scale and a turn about its own axis (a sphere,
    which takes a uniform scale only, is placed by centre and radius); a
    mesh (an icosphere) has face normals, as Mitsuba's sampling of a mesh
    light uses the interpolated normal where it has vertex normals.
    ``radiance`` scales the place's own."""
    center, size, turn, place_radiance, _ = LIGHT_PLACES[place]
    emitter = {"type": "area", "radiance": radiance * place_radiance}
    bsdf = {"type": "diffuse", "reflectance": 0.3}
    if shape == "sphere":
        return {"type": "sphere", "center": list(center), "radius": size * 0.6,
                "emitter": emitter, "bsdf": bsdf}
    flat = shape in ("rectangle", "disk")
    scale = (size, 0.6 * size, 1.0) if flat else (size, 0.6 * size, 0.7 * size)
    rotate = [("z", 30.0)] + (turn if flat else [("x", 20.0), ("y", 35.0)])
    m = transform(center, rotate, scale)
    if shape == "mesh":
        v, f = icosphere(1)
        v = v @ m[:3, :3].T + m[:3, 3]
        return {"type": "mesh", "vertices": v, "faces": f, "face_normals": True,
                "emitter": emitter, "bsdf": bsdf}
    return {"type": shape, "to_world": m, "emitter": emitter, "bsdf": bsdf}


def area_lit_floor(shape: str, place: str, width: int = 32, height: int = 24) -> dict:
    """A diffuse floor lit by one area light (:func:`area_light`), seen
    from above so that the lit floor fills the frame."""
    origin, target = LIGHT_PLACES[place][4]
    return {"type": "scene",
            "sensor": sensor(origin=origin, target=target, fov=45.0, width=width,
                             height=height),
            "floor": ground(size=6.0, reflectance=0.6),
            "light": area_light(shape, place)}


def lit_room(strategy_light: str = "rectangle", width: int = 32, height: int = 24) -> dict:
    """A closed room (the cube [-1, 1]³ seen from inside, diffuse walls)
    lit only by a small light near the ceiling that faces it: the room is
    lit by what the ceiling reflects, so every path has three segments or
    more."""
    room = {"type": "cube", "flip_normals": True,
            "bsdf": {"type": "diffuse", "reflectance": [0.7, 0.6, 0.5]}}
    light = dict(area_light(strategy_light, "near", radiance=5.0))
    if strategy_light in ("rectangle", "disk"):
        # Facing up, 0.2 under the ceiling.
        light["to_world"] = transform((0.1, 0.8, -0.2), [("x", -90.0), ("z", 20.0)],
                                      (0.15, 0.1, 1.0))
    return {"type": "scene",
            "sensor": sensor(origin=(0.0, -0.2, 0.95), target=(0.0, 0.1, -1.0), fov=70.0,
                             width=width, height=height),
            "integrator": {"type": "path", "max_depth": 6, "hide_emitters": True},
            "room": room, "light": light}


def skip_scalar(mi):
    """Skips a comparison with Mitsuba's gaussian filter under its scalar
    variants, which splat with a 31-step table of the filter rather than
    the filter (its llvm variants, chosen where a libLLVM works, use it)."""
    if mi.variant().startswith("scalar"):
        pytest.skip("Mitsuba's scalar variants splat a step table of the gaussian")
