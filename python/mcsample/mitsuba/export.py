"""An :class:`mcsample.Scene` as a Mitsuba 3 scene dict: the same camera,
film (its box or gaussian filter), shapes, materials (mcsample's Phong as the
``mcsample_phong`` plugin) and lights. Meshes go in as ``mi.Mesh`` objects
built in memory (no files); a non-lat-long envmap is converted to lat-long,
the only form Mitsuba's envmap emitter takes."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .emitters import envmap_dict
from .phong import register_phong

if TYPE_CHECKING:
    from ..scene import Scene
    from ..scene.parse import Material, ShapeRecord

__all__ = ["scene_dict"]


def _rgb(value: list[float]) -> dict[str, Any]:
    return {"type": "rgb", "value": value}


def _bsdf(material: "Material", phong_type: str) -> dict[str, Any]:
    if material.kind == "diffuse":
        inner: dict[str, Any] = {"type": "diffuse", "reflectance": _rgb(material.diffuse)}
    else:
        inner = {"type": phong_type, "diffuse_reflectance": _rgb(material.diffuse),
                 "specular_reflectance": _rgb(material.specular),
                 "exponent": material.exponent}
    return {"type": "twosided", "bsdf": inner} if material.two_sided else inner


def _mesh(mi: Any, name: str, shape: "ShapeRecord", bsdf: dict[str, Any],
          emitter: dict[str, Any] | None) -> Any:
    """A ``mi.Mesh`` of the shape's world-space triangles (and vertex
    normals unless it has face normals), with its BSDF and emitter, in any
    variant (JIT or scalar)."""
    v = np.ascontiguousarray(shape.vertices, dtype=np.float32)
    f = np.ascontiguousarray(shape.faces, dtype=np.uint32)
    normals = None if shape.face_normals or shape.normals is None else shape.normals
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf)
    if emitter is not None:
        props["emitter"] = mi.load_dict(emitter)
    props["face_normals"] = normals is None
    mesh = mi.Mesh(name, len(v), len(f), props=props, has_vertex_normals=normals is not None)
    params = mi.traverse(mesh)
    buffers = {"vertex_positions": v, "faces": f}
    if normals is not None:
        buffers["vertex_normals"] = np.ascontiguousarray(normals, dtype=np.float32)
    for key, rows in buffers.items():
        # The rows one after the other (x0, y0, z0, x1, ...), as the flat
        # array type the variant keeps the buffer in: a Dr.Jit array in
        # a JIT variant, a dynamic scalar array in a scalar one (where
        # `mi.Point3f` is one point and cannot take them all).
        params[key] = type(params[key])(rows.ravel())
    params.update()
    return mesh


def scene_dict(scene: "Scene", spp: int | None = None,
               latlong_width: int | None = None) -> dict[str, Any]:
    """A dict for ``mi.load_dict`` that renders ``scene`` (a Mitsuba variant
    must be set; the Phong plugin is registered for it here). ``spp`` sets
    the sampler's ``sample_count`` (default: the scene's, else 4);
    ``latlong_width`` the columns of a converted envmap (default 4× the
    source's resolution)."""
    c = scene.camera
    if c.shutter_close > c.shutter_open:
        moving = [s.key for s in scene.shapes if s.motion is not None]
        if c.to_world_end is not None:
            moving.insert(0, "sensor")
        if moving:
            raise ValueError(f"{moving[0]}: it moves during the shutter (to_world_end), and "
                             "Mitsuba 3.9 has no motion blur")
    import mitsuba as mi

    phong_type = register_phong()
    sensor: dict[str, Any] = {
        "type": "thinlens" if c.aperture_radius > 0 else "perspective",
        "fov": c.fov, "fov_axis": c.fov_axis, "near_clip": c.near_clip,
        "far_clip": c.far_clip, "to_world": mi.ScalarTransform4f(c.to_world.tolist()),
        "film": {"type": "hdrfilm", "width": c.width, "height": c.height,
                 "rfilter": ({"type": "gaussian", "stddev": c.stddev}
                             if c.rfilter == "gaussian" else {"type": "box"}),
                 "sample_border": c.sample_border, "pixel_format": "rgb"},
        "sampler": {"type": c.sampler, "sample_count": int(spp or c.sample_count or 4)},
    }
    if c.aperture_radius > 0:
        sensor.update(aperture_radius=c.aperture_radius, focus_distance=c.focus_distance)
    out: dict[str, Any] = {"type": "scene", "sensor": sensor}
    for i, s in enumerate(scene.shapes):
        bsdf = _bsdf(s.material, phong_type)
        emitter = None if s.emission is None else {"type": "area", "radiance": _rgb(s.emission)}
        if s.kind == "mesh":
            out[f"shape{i}"] = _mesh(mi, f"shape{i}", s, bsdf, emitter)
            continue
        d: dict[str, Any]
        if s.kind == "sphere":
            d = {"type": "sphere", "center": s.center, "radius": s.radius,
                 "flip_normals": s.flip_normals}
        else:
            d = {"type": "disk", "to_world": mi.ScalarTransform4f(s.to_world.tolist())}
        d["bsdf"] = bsdf
        if emitter is not None:
            d["emitter"] = emitter
        out[f"shape{i}"] = d
    if scene.environment is not None:
        kind, value = scene.environment
        out["environment"] = ({"type": "constant", "radiance": _rgb(value)}
                              if kind == "constant" else envmap_dict(value, latlong_width))
    return out
