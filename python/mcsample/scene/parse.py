"""Reading Mitsuba 3 scene dicts: the shapes, materials, lights, camera and
integrator settings of the subset :mod:`mcsample.scene` documents, as plain
records in world space."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .._core import EnvMap, Phong
from .._core.io import read_mesh
from .serialized import read_serialized

__all__ = ["Camera", "Material", "ParsedScene", "ShapeRecord", "look_at", "parse_scene"]


#: Mitsuba's default film size and field of view (focal length 50 mm on a
#: 36 mm wide film).
DEFAULT_WIDTH, DEFAULT_HEIGHT = 768, 576


def look_at(origin: Any, target: Any, up: Any) -> np.ndarray:
    """The 4×4 camera-to-world matrix of Mitsuba's ``look_at``: camera +z
    toward ``target``, +y along ``up`` (made orthogonal), +x = up × dir."""
    o, t, u = (np.asarray(v, dtype=np.float64).reshape(3) for v in (origin, target, up))
    d = t - o
    if not np.linalg.norm(d) > 0:
        raise ValueError("look_at: origin and target must differ")
    d /= np.linalg.norm(d)
    left = np.cross(u, d)
    if not np.linalg.norm(left) > 0:
        raise ValueError("look_at: up must not be parallel to target - origin")
    left /= np.linalg.norm(left)
    new_up = np.cross(d, left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, new_up, d, o
    return m


def _matrix(value: Any, key: str) -> np.ndarray:
    """A 4×4 float64 matrix from a Mitsuba transform, an array-like or a
    ``{"look_at": {...}}`` dict."""
    if isinstance(value, Mapping):
        if set(value) != {"look_at"}:
            raise ValueError(f"{key}: a dict transform must be {{'look_at': {{...}}}}")
        la = dict(value["look_at"])
        unknown = set(la) - {"origin", "target", "up"}
        if unknown or len(la) != 3:
            raise ValueError(f"{key}.look_at needs exactly origin, target and up")
        return look_at(la["origin"], la["target"], la["up"])
    source = value.matrix if hasattr(value, "matrix") and not hasattr(value, "shape") else value
    try:
        m = np.asarray(source, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{key} must be a 4x4 matrix or a Mitsuba transform: {e}") from None
    m = m.reshape(m.shape[:2]) if m.ndim == 3 and m.shape[2] == 1 else m
    if m.shape != (4, 4):
        raise ValueError(f"{key} must be a 4x4 matrix, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ValueError(f"{key} has entries that are not finite")
    return m


#: Linear sRGB of the equal-energy spectrum of luminance 1 (the rows of the
#: XYZ → sRGB matrix, summed): what Mitsuba's RGB variants make of an
#: emitter's ``{"type": "spectrum", "value": v}`` (v times this; a
#: reflectance's is v in every channel).
EQUAL_ENERGY_SRGB = (1.2047843, 0.9483008, 0.9088427)


def _rgb(value: Any, key: str, emission: bool = False) -> list[float]:
    if isinstance(value, Mapping):
        kind = value.get("type")
        if kind not in ("rgb", "spectrum") or set(value) - {"type", "value"}:
            raise ValueError(f"{key}: only constant colours are supported (a float, an RGB "
                             "triple, {'type': 'rgb', 'value': ...} or {'type': 'spectrum', "
                             "'value': float})")
        if kind == "spectrum":
            v = _float(value.get("value", 1.0), f"{key}.value")
            value = [v * c for c in EQUAL_ENERGY_SRGB] if emission else v
        else:
            value = value["value"]
    try:
        rgb = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,))
    except (TypeError, ValueError):
        raise ValueError(f"{key} must be a float or an RGB triple, got {value!r}") from None
    if not np.all(np.isfinite(rgb)) or np.any(rgb < 0):
        raise ValueError(f"{key} = {value!r}: must be finite and >= 0")
    return [float(v) for v in rgb]


def _float(value: Any, key: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{key} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{key} = {x}: must be finite")
    return x


def _check_keys(d: Mapping[str, Any], allowed: set[str], where: str) -> None:
    for k in d:
        if k not in allowed and k not in ("type", "id"):
            raise ValueError(f"{where}.{k}: not supported by mcsample "
                             f"(supported: {', '.join(sorted(allowed)) or 'none'})")


@dataclass
class Material:
    """A Phong BRDF (diffuse is Phong with no specular part) and its sides."""
    diffuse: list[float]
    specular: list[float]
    exponent: float
    two_sided: bool
    kind: str  # "diffuse" or "phong"

    def phong(self) -> Phong:
        return Phong(self.diffuse, self.specular, self.exponent)


DEFAULT_MATERIAL = Material([0.5] * 3, [0.0] * 3, 0.0, False, "diffuse")
EMITTER_MATERIAL = Material([0.0] * 3, [0.0] * 3, 0.0, False, "diffuse")


@dataclass
class ShapeRecord:
    """One shape in world space, as mcsample renders it."""
    kind: str  # "mesh", "sphere" or "disk"
    material: Material
    emission: list[float] | None
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    normals: np.ndarray | None = None
    face_normals: bool = False
    center: list[float] | None = None
    radius: float = 1.0
    flip_normals: bool = False
    to_world: np.ndarray | None = None
    #: The transform at shutter_open and at shutter_close (``to_world``, or
    #: the identity, and ``to_world_end``) of a shape that moves; the
    #: geometry above is where it is at shutter_open.
    motion: tuple[np.ndarray, np.ndarray] | None = None
    #: The shape's key in the scene dict.
    key: str = ""


@dataclass
class Camera:
    to_world: np.ndarray
    fov: float
    fov_axis: str = "x"
    width: int = DEFAULT_WIDTH
    height: int = DEFAULT_HEIGHT
    near_clip: float = 1e-2
    far_clip: float = 1e4
    aperture_radius: float = 0.0
    focus_distance: float = 0.0
    sample_count: int | None = None
    #: The sensor's sampler, by its Mitsuba name.
    sampler: str = "independent"
    #: The shutter interval (Mitsuba's sensor keys; equal: no motion blur)
    #: and, for a moving camera, its ``to_world`` at shutter_close.
    shutter_open: float = 0.0
    shutter_close: float = 0.0
    to_world_end: np.ndarray | None = None
    #: The film's reconstruction filter, Mitsuba's ``"gaussian"`` (its
    #: default) or ``"box"``, the Gaussian's standard deviation in pixels,
    #: and whether samples also fall on the filter's border around the film.
    rfilter: str = "gaussian"
    stddev: float = 0.5
    sample_border: bool = False


#: Mitsuba's samplers, the keys each takes, and the mcsample sampler that
#: does the same (``orthogonal``'s orthogonal arrays stratify each 1D and 2D
#: projection, as the multi-jittered pattern does; ``ldsampler`` is
#: mcsample's sampler of that name: the padded (0, 2)-sequences of "sobol",
#: shuffled per pixel and dimension, randomised by a digital shift as
#: Mitsuba's are, not by Owen's scramble).
MITSUBA_SAMPLERS: dict[str, tuple[set[str], str]] = {
    "independent": ({"sample_count", "seed"}, "independent"),
    "stratified": ({"sample_count", "seed", "jitter"}, "stratified"),
    "multijitter": ({"sample_count", "seed", "jitter"}, "multijitter"),
    "orthogonal": ({"sample_count", "seed", "jitter", "strength"}, "multijitter"),
    "ldsampler": ({"sample_count", "seed"}, "ldsampler"),
}


def _material(d: Any, key: str, refs: Mapping[str, Material]) -> Material:
    if not isinstance(d, Mapping) or "type" not in d:
        raise ValueError(f"{key} must be a bsdf dict with a 'type'")
    kind = d["type"]
    if kind == "ref":
        _check_keys(d, set(), key)
        if d.get("id") not in refs:
            raise ValueError(f"{key}: no top-level bsdf with id {d.get('id')!r}")
        return refs[d["id"]]
    if kind == "twosided":
        _check_keys(d, {"bsdf"}, key)
        inner = _material(d["bsdf"], f"{key}.bsdf", refs)
        return Material(inner.diffuse, inner.specular, inner.exponent, True, inner.kind)
    if kind == "diffuse":
        _check_keys(d, {"reflectance"}, key)
        rho = _rgb(d.get("reflectance", 0.5), f"{key}.reflectance")
        return Material(rho, [0.0] * 3, 0.0, False, "diffuse")
    if kind == "mcsample_phong":
        _check_keys(d, {"diffuse_reflectance", "specular_reflectance", "exponent"}, key)
        m = Material(_rgb(d.get("diffuse_reflectance", 0.5), f"{key}.diffuse_reflectance"),
                     _rgb(d.get("specular_reflectance", 0.2), f"{key}.specular_reflectance"),
                     _float(d.get("exponent", 30.0), f"{key}.exponent"), False, "phong")
        m.phong()  # energy conservation and exponent checks, with their messages
        return m
    raise ValueError(f"{key}.type = {kind!r}: mcsample supports the bsdfs 'diffuse', "
                     "'mcsample_phong', 'twosided' and 'ref'")


def _transform_mesh(v: np.ndarray, n: np.ndarray | None, m: np.ndarray | None):
    if m is None:
        return v, n
    v = v @ m[:3, :3].T + m[:3, 3]
    if n is not None:
        n = n @ np.linalg.inv(m[:3, :3])  # inverse transpose, row vectors
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    return v, n


def _rectangle() -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
    return v, np.array([[0, 1, 2], [2, 3, 0]], dtype=np.int64)


def _cube() -> tuple[np.ndarray, np.ndarray]:
    verts, faces = [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            # Two in-plane axes ordered so that (a × b) points along +sign·axis.
            a, b = (axis + 1) % 3, (axis + 2) % 3
            if sign < 0:
                a, b = b, a
            base = len(verts)
            for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = np.zeros(3)
                p[axis], p[a], p[b] = sign, s, t
                verts.append(p)
            faces += [[base, base + 1, base + 2], [base + 2, base + 3, base]]
    return np.array(verts), np.array(faces, dtype=np.int64)


_SHAPE_KEYS = {
    "sphere": {"center", "radius", "to_world", "flip_normals", "to_world_end"},
    "rectangle": {"to_world", "flip_normals", "to_world_end"},
    "disk": {"to_world", "flip_normals", "to_world_end"},
    "cube": {"to_world", "flip_normals", "to_world_end"},
    "ply": {"filename", "to_world", "face_normals", "flip_normals", "to_world_end"},
    "obj": {"filename", "to_world", "face_normals", "flip_normals", "to_world_end"},
    "serialized": {"filename", "shape_index", "to_world", "face_normals", "flip_normals", "to_world_end"},
    "mesh": {"vertices", "faces", "normals", "to_world", "face_normals", "flip_normals", "to_world_end"},
}


def _motion_end(start: np.ndarray, value: Any, key: str) -> np.ndarray:
    """The transform ``value`` at shutter_close of something whose
    transform at shutter_open is ``start``: a 4×4 affine map, invertible,
    and mirroring exactly when ``start`` does (so a rotation takes one to
    the other)."""
    end = _matrix(value, key)
    if not np.allclose(end[3], [0, 0, 0, 1]):
        raise ValueError(f"{key}: the last row must be (0, 0, 0, 1) (an affine transform)")
    det0, det1 = np.linalg.det(start[:3, :3]), np.linalg.det(end[:3, :3])
    if det0 == 0:
        raise ValueError(f"{key}: the transform at shutter_open (to_world) is singular")
    if det1 == 0:
        raise ValueError(f"{key}: the transform is singular")
    if (det0 < 0) != (det1 < 0):
        raise ValueError(f"{key}: one end of the motion mirrors the shape and the other "
                         "does not")
    return end


def _shape(d: Mapping[str, Any], key: str, refs: Mapping[str, Material]) -> ShapeRecord:
    kind = d["type"]
    _check_keys(d, _SHAPE_KEYS[kind] | {"bsdf", "emitter"}, key)
    if "bsdf" in d:
        material = _material(d["bsdf"], f"{key}.bsdf", refs)
    else:
        # Mitsuba's default: diffuse 0.5, black on a shape that emits.
        material = EMITTER_MATERIAL if "emitter" in d else DEFAULT_MATERIAL
    emission = None
    if "emitter" in d:
        e = d["emitter"]
        if not isinstance(e, Mapping) or e.get("type") != "area":
            raise ValueError(f"{key}.emitter: only {{'type': 'area', 'radiance': ...}} "
                             "emitters can sit on a shape")
        _check_keys(e, {"radiance"}, f"{key}.emitter")
        emission = _rgb(e.get("radiance", 1.0), f"{key}.emitter.radiance", emission=True)
    m = _matrix(d["to_world"], f"{key}.to_world") if "to_world" in d else None
    flip = bool(d.get("flip_normals", False))
    rec = ShapeRecord(kind="mesh", material=material, emission=emission, flip_normals=flip,
                      key=key)
    if "to_world_end" in d:
        start = m if m is not None else np.eye(4)
        end = _motion_end(start, d["to_world_end"], f"{key}.to_world_end")
        if emission is not None:
            raise ValueError(f"{key}.to_world_end: a moving area light is not supported "
                             "(only shapes that do not emit may move)")
        if kind == "sphere":
            scales = np.linalg.norm(end[:3, :3], axis=0)
            if not np.allclose(scales, scales[0], rtol=1e-5):
                raise ValueError(f"{key}.to_world_end: a sphere takes a uniform scale only")
        if not np.array_equal(start, end):
            rec.motion = (start, end)
    if kind == "sphere":
        center = np.asarray(d.get("center", [0.0, 0.0, 0.0]), dtype=np.float64).reshape(3)
        radius = _float(d.get("radius", 1.0), f"{key}.radius")
        if m is not None:
            scales = np.linalg.norm(m[:3, :3], axis=0)
            if not np.allclose(scales, scales[0], rtol=1e-5):
                raise ValueError(f"{key}.to_world: a sphere takes a uniform scale only")
            center = m[:3, :3] @ center + m[:3, 3]
            radius *= float(scales[0])
        rec.kind, rec.center, rec.radius = "sphere", [float(c) for c in center], radius
        return rec
    if kind == "disk":
        rec.kind = "disk"
        rec.to_world = m if m is not None else np.eye(4)
        if flip:
            rec.to_world = rec.to_world @ np.diag([1.0, -1.0, -1.0, 1.0])
        return rec
    if kind in ("rectangle", "cube"):
        v, f = _rectangle() if kind == "rectangle" else _cube()
        n, rec.face_normals = None, True
    elif kind == "mesh":
        try:
            v = np.asarray(d["vertices"], dtype=np.float64)
            f = np.asarray(d["faces"])
        except KeyError:
            raise ValueError(f"{key}: a mesh needs 'vertices' and 'faces'") from None
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
            raise ValueError(f"{key}: vertices must be (N, 3) and faces (M, 3), "
                             f"got {v.shape} and {f.shape}")
        if not np.issubdtype(f.dtype, np.integer):
            raise ValueError(f"{key}.faces must hold integers, got {f.dtype}")
        f = f.astype(np.int64)
        n = None if d.get("normals") is None else np.asarray(d["normals"], dtype=np.float64)
        rec.face_normals = bool(d.get("face_normals", False))
    else:
        if "filename" not in d:
            raise ValueError(f"{key}: a {kind} shape needs a 'filename'")
        if kind == "serialized":
            index = d.get("shape_index", 0)
            v, f, n = read_serialized(os.fspath(d["filename"]), index)
        else:
            v, f, n = read_mesh(os.fspath(d["filename"]))
        rec.face_normals = bool(d.get("face_normals", False))
    # Mitsuba's rectangle and cube face where to_world's inverse transpose
    # takes their normals, also through a mirror (a mirror reverses their
    # corners' order); a mesh read from a file keeps its winding.
    mirrored = kind in ("rectangle", "cube") and m is not None and np.linalg.det(m[:3, :3]) < 0
    if flip != mirrored:
        f = f[:, ::-1].copy()
    if flip:
        n = None if n is None else -n
    rec.vertices, rec.normals = _transform_mesh(v, n, m)
    rec.faces = f
    return rec


def _environment(d: Any, key: str) -> tuple[str, Any]:
    if isinstance(d, EnvMap):
        return "envmap", d
    kind = d["type"]
    if kind == "constant":
        _check_keys(d, {"radiance"}, key)
        return "constant", _rgb(d.get("radiance", 1.0), f"{key}.radiance", emission=True)
    _check_keys(d, {"filename", "scale", "to_world"}, key)
    if "filename" not in d:
        raise ValueError(f"{key}: an envmap needs a 'filename' (or give an mcsample.EnvMap)")
    to_world = _matrix(d["to_world"], f"{key}.to_world") if "to_world" in d else None
    scale = _float(d.get("scale", 1.0), f"{key}.scale")
    return "envmap", EnvMap.load(os.fspath(d["filename"]), to_world=to_world, scale=scale)


def _camera(d: Mapping[str, Any], key: str) -> Camera:
    kind = d["type"]
    # A pinhole ignores focus_distance (mi.cornell_box() gives one), as
    # Mitsuba does.
    lens = {"aperture_radius", "focus_distance"} if kind == "thinlens" else {"focus_distance"}
    _check_keys(d, {"fov", "fov_axis", "to_world", "near_clip", "far_clip", "film", "sampler",
                    "shutter_open", "shutter_close", "to_world_end"} | lens, key)
    if "fov" not in d:
        raise ValueError(f"{key}: give the field of view as 'fov' (degrees); "
                         "'focal_length' is not supported")
    cam = Camera(to_world=_matrix(d["to_world"], f"{key}.to_world") if "to_world" in d
                 else np.eye(4), fov=_float(d["fov"], f"{key}.fov"),
                 fov_axis=str(d.get("fov_axis", "x")),
                 near_clip=_float(d.get("near_clip", 1e-2), f"{key}.near_clip"),
                 far_clip=_float(d.get("far_clip", 1e4), f"{key}.far_clip"))
    cam.shutter_open = _float(d.get("shutter_open", 0.0), f"{key}.shutter_open")
    cam.shutter_close = _float(d.get("shutter_close", 0.0), f"{key}.shutter_close")
    if not (np.isfinite(cam.shutter_open) and np.isfinite(cam.shutter_close)
            and cam.shutter_close >= cam.shutter_open):
        raise ValueError(f"{key}.shutter_close = {cam.shutter_close}: must be finite and >= "
                         f"shutter_open = {cam.shutter_open}")
    if "to_world_end" in d:
        end = _motion_end(cam.to_world, d["to_world_end"], f"{key}.to_world_end")
        if not np.array_equal(end, cam.to_world):
            cam.to_world_end = end
    if kind == "thinlens":
        cam.aperture_radius = _float(d.get("aperture_radius", 0.03), f"{key}.aperture_radius")
        cam.focus_distance = _float(d.get("focus_distance", 0.0), f"{key}.focus_distance")
    film = d.get("film", {"type": "hdrfilm"})
    if film.get("type") != "hdrfilm":
        raise ValueError(f"{key}.film.type = {film.get('type')!r}: must be 'hdrfilm'")
    # component_format float32 is the default storage (others round).
    _check_keys(film, {"width", "height", "rfilter", "pixel_format", "component_format",
                       "sample_border"}, f"{key}.film")
    if film.get("component_format", "float32") != "float32":
        raise ValueError(f"{key}.film.component_format must be 'float32' (others round the "
                         "image)")
    cam.width = int(film.get("width", DEFAULT_WIDTH))
    cam.height = int(film.get("height", DEFAULT_HEIGHT))
    # Mitsuba's default filter is its gaussian.
    rfilter = film.get("rfilter", {"type": "gaussian"})
    cam.rfilter = str(rfilter.get("type"))
    if cam.rfilter == "gaussian":
        _check_keys(rfilter, {"stddev"}, f"{key}.film.rfilter")
        cam.stddev = _float(rfilter.get("stddev", 0.5), f"{key}.film.rfilter.stddev")
        if not 0 < cam.stddev <= 64:
            raise ValueError(f"{key}.film.rfilter.stddev = {cam.stddev}: must lie in (0, 64] "
                             "pixels")
    elif cam.rfilter == "box":
        _check_keys(rfilter, set(), f"{key}.film.rfilter")
    else:
        raise ValueError(f"{key}.film.rfilter.type = {cam.rfilter!r}: must be 'gaussian' or "
                         "'box'")
    cam.sample_border = bool(film.get("sample_border", False))
    if film.get("pixel_format", "rgb") not in ("rgb", "rgba"):
        raise ValueError(f"{key}.film.pixel_format must be 'rgb' or 'rgba'")
    sampler = d.get("sampler")
    if sampler is not None:
        kind = sampler.get("type")
        if kind not in MITSUBA_SAMPLERS:
            raise ValueError(f"{key}.sampler.type = {kind!r}: must be one of "
                             f"{', '.join(map(repr, MITSUBA_SAMPLERS))}")
        _check_keys(sampler, MITSUBA_SAMPLERS[kind][0], f"{key}.sampler")
        if not sampler.get("jitter", True):
            raise ValueError(f"{key}.sampler.jitter = False is not supported (strata are "
                             "always jittered)")
        if int(sampler.get("strength", 2)) != 2:
            raise ValueError(f"{key}.sampler.strength must be 2")
        cam.sampler = kind
        cam.sample_count = int(sampler.get("sample_count", 4))
    return cam


@dataclass
class ParsedScene:
    """What a Mitsuba scene dict describes, in mcsample's terms."""
    shapes: list[ShapeRecord]
    environment: tuple[str, Any] | None
    camera: Camera
    integrator: dict[str, Any]


def parse_scene(d: Mapping[str, Any]) -> ParsedScene:
    """Reads a Mitsuba 3 scene dict (the subset in :mod:`mcsample.scene`).

    Raises ValueError naming the first key outside that subset or with a
    bad value, OSError for a mesh or image file that cannot be read.
    """
    if not isinstance(d, Mapping) or d.get("type") != "scene":
        raise ValueError("a scene dict has 'type': 'scene' at the top level")
    refs: dict[str, Material] = {}
    for key, value in d.items():
        if isinstance(value, Mapping) and value.get("type") in (
                "diffuse", "mcsample_phong", "twosided"):
            refs[str(value.get("id", key))] = _material(value, key, refs)
    shapes, environment, camera, integrator = [], None, None, {}
    for key, value in d.items():
        if key == "type":
            continue
        kind = value.get("type") if isinstance(value, Mapping) else None
        if isinstance(value, EnvMap) or kind in ("envmap", "constant"):
            if environment is not None:
                raise ValueError(f"{key}: a scene holds at most one environment emitter")
            environment = _environment(value, key)
        elif kind in _SHAPE_KEYS:
            shapes.append(_shape(value, key, refs))
        elif kind in ("perspective", "thinlens"):
            if camera is not None:
                raise ValueError(f"{key}: mcsample renders scenes with one sensor")
            camera = _camera(value, key)
        elif kind in ("path", "direct", "ptracer"):
            # samples_per_pass only splits Mitsuba's work into passes.
            _check_keys(value, {"max_depth", "rr_depth", "hide_emitters"}
                        | ({"samples_per_pass"} if kind == "ptracer" else set()), key)
            integrator = {"integrator": kind,
                          **{k: int(value[k]) for k in ("max_depth", "rr_depth")
                             if k in value}}
            if "hide_emitters" in value:
                integrator["hide_emitters"] = bool(value["hide_emitters"])
        elif kind in ("diffuse", "mcsample_phong", "twosided"):
            continue  # a top-level bsdf, referenced by id
        else:
            raise ValueError(f"{key}: type {kind!r} is not supported by mcsample "
                             "(see mcsample.scene for the subset it reads)")
    if camera is None:
        raise ValueError("the scene has no sensor ('perspective' or 'thinlens')")
    return ParsedScene(shapes, environment, camera, integrator)
