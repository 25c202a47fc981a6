"""Scenes described by the Mitsuba 3 scene dictionary.

``Scene.from_mitsuba(d)`` reads the subset of Mitsuba's dictionary format
that mcsample renders, and ``Scene.from_mitsuba("scene.xml")`` the same
subset from a Mitsuba 3 XML file (:func:`read_xml`); ``scene.to_mitsuba()`` gives back a dictionary that
``mi.load_dict`` renders to the same image (with mcsample's Phong registered
as the ``"mcsample_phong"`` plugin, see :func:`mcsample.mitsuba.register_phong`).

The subset (anything else raises ValueError naming the key):

- shapes: ``sphere`` (center, radius, to_world, flip_normals), ``rectangle``,
  ``disk``, ``cube``, ``ply`` and ``obj`` (filename, face_normals,
  flip_normals, to_world), ``serialized`` (also shape_index; Mitsuba's
  compressed meshes, read by :func:`read_serialized`), and ``mesh`` — mcsample's own type for numpy
  arrays: ``vertices`` (N, 3), ``faces`` (M, 3) and optional ``normals``
  (N, 3). Each may hold a ``bsdf`` and an ``area`` emitter (``radiance``),
  and a ``to_world_end``: its transform at shutter_close (``to_world`` being
  the one at shutter_open; in between, translation and scale interpolated
  linearly, rotation by slerp), for motion blur (not on an emitter).
- bsdfs: ``diffuse`` (reflectance), ``mcsample_phong`` (diffuse_reflectance,
  specular_reflectance, exponent), ``twosided`` around either, and
  ``{"type": "ref", "id": ...}`` to a top-level bsdf. A shape without one
  gets Mitsuba's default: diffuse 0.5, or black diffuse if it emits.
- emitters: ``envmap`` (filename, scale, to_world; or an :class:`EnvMap`
  given directly as the value, in any mapping) and ``constant`` (radiance).
- sensors: ``perspective`` (fov, fov_axis, near_clip, far_clip, to_world;
  focus_distance accepted and ignored, as Mitsuba does) and ``thinlens``
  (also aperture_radius, focus_distance), shutter_open / shutter_close (the
  interval over which each sample's time is drawn; both 0 by default, as
  Mitsuba's; equal: no motion blur) and ``to_world_end`` (a moving camera), with an ``hdrfilm`` (width,
  height, ``rfilter``: ``gaussian`` (stddev; Mitsuba's default, also when
  ``rfilter`` is absent) or ``box``, sample_border; pixel_format and
  component_format "float32" accepted) and a sampler:
  ``independent``, ``stratified``, ``multijitter``, ``orthogonal`` or
  ``ldsampler`` (sample_count: the default spp; the type: the default
  ``sampler=`` of :func:`mcsample.render`, see ``MITSUBA_SAMPLERS`` in
  :mod:`mcsample.scene.parse`).
- ``integrator``: ``path``, ``direct`` or ``ptracer`` (max_depth, rr_depth,
  hide_emitters; ptracer's samples_per_pass is accepted): the
  defaults of :func:`mcsample.render`.

Colours are a float, an RGB triple, ``{"type": "rgb", "value": ...}`` or
``{"type": "spectrum", "value": v}`` (constant: on an emitter, as Mitsuba's
RGB variants take it, the equal-energy spectrum's colour times v).
``to_world`` is a Mitsuba transform, a 4×4 array-like, or (handy in JSON)
``{"look_at": {"origin": ..., "target": ..., "up": ...}}``.
"""

from __future__ import annotations

import copy
import os
import re
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from .._core.render import CompiledScene, SceneBuilder
from ..results import EmitterSample, SensorSample
from .meshes import bumpy_sphere, icosphere
from .parse import Camera, ShapeRecord, look_at, parse_scene
from .serialized import read_serialized
from .xml import read_xml, read_xml_located

__all__ = ["EmitterSample", "Scene", "SensorSample", "bumpy_sphere", "icosphere", "look_at", "read_serialized", "read_xml"]


@dataclass
class Scene:
    """A scene mcsample can render and Mitsuba 3 can render too.

    Build one with :meth:`from_mitsuba`; render it with
    :func:`mcsample.render`, and in Mitsuba with
    :func:`mcsample.mitsuba.render_reference`.
    """

    shapes: list[ShapeRecord]
    environment: tuple[str, Any] | None
    camera: Camera
    integrator: dict[str, Any] = field(default_factory=dict)
    source: dict[str, Any] = field(default_factory=dict, repr=False)
    _compiled: CompiledScene | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        kinds: dict[str, int] = {}
        for shape in self.shapes:
            kinds[shape.kind] = kinds.get(shape.kind, 0) + 1
        shapes = ", ".join(f"{k} x{n}" for k, n in kinds.items())
        lights = sum(s.emission is not None for s in self.shapes)
        env = "no environment"
        if self.environment is not None:
            kind, value = self.environment
            env = repr(value) if kind != "constant" else f"constant {value}"
        c = self.camera
        return (f"Scene({shapes}; {lights} area lights; {env}; camera {c.width}x{c.height}, "
                f"fov {c.fov:g} ({c.fov_axis}))")

    def __getstate__(self) -> dict[str, Any]:
        """Pickles without the compiled scene (built again on first use,
        to the same bits)."""
        return {**self.__dict__, "_compiled": None}

    @classmethod
    def from_mitsuba(cls, d: Mapping[str, Any] | str | os.PathLike[str],
                     **parameters: Any) -> "Scene":
        """Reads a Mitsuba 3 scene dict (the subset in this module's doc), or
        a Mitsuba 3 XML scene file (a path; see :func:`read_xml`), with
        ``parameters`` for its ``$name`` references as ``mi.load_file``
        takes them.

        Raises ValueError naming the first key outside that subset or with a
        bad value (for a file, with the file and line it was read from),
        OSError for a scene, mesh or image file that cannot be read.
        """
        if isinstance(d, (str, os.PathLike)):
            d, where = read_xml_located(d, **parameters)
            try:
                p = parse_scene(d)
            except ValueError as e:
                # The top-level key the message starts with (the longest:
                # "shape_10." is not "shape_1").
                keys = [k for k in where if re.match(re.escape(k) + r"[.:\s]", str(e))]
                if not keys:
                    raise
                raise ValueError(f"{where[max(keys, key=len)]}: {e}") from None
        elif parameters:
            raise ValueError("parameters are for a scene file; a dict has none: "
                             f"{', '.join(parameters)}")
        else:
            p = parse_scene(d)
        return cls(p.shapes, p.environment, p.camera, p.integrator, source=dict(d))

    @property
    def compiled(self) -> CompiledScene:
        """The Rust scene (BVH and light selection), built on first use."""
        if self._compiled is None:
            b = SceneBuilder()
            c = self.camera
            # A shutter of length 0 sees everything where it is at
            # shutter_open.
            blur = c.shutter_close > c.shutter_open
            for s in self.shapes:
                bsdf, two = s.material.phong(), s.material.two_sided
                if s.kind == "sphere":
                    b.add_sphere(s.center, s.radius, s.flip_normals, bsdf, two, s.emission)
                elif s.kind == "disk":
                    b.add_disk(s.to_world.tolist(), bsdf, two, s.emission)
                else:
                    b.add_mesh(np.ascontiguousarray(s.vertices),
                               np.ascontiguousarray(s.faces),
                               None if s.normals is None else np.ascontiguousarray(s.normals),
                               s.face_normals, bsdf, two, s.emission)
                if s.motion is not None and blur:
                    b.set_motion(s.motion[0].tolist(), s.motion[1].tolist())
            if self.environment is not None:
                kind, value = self.environment
                if kind == "envmap":
                    b.set_envmap(value)
                else:
                    b.set_constant(value)
            b.set_camera(c.to_world.tolist(), c.fov, c.fov_axis, c.width, c.height,
                         c.near_clip, c.far_clip, c.aperture_radius, c.focus_distance)
            if c.to_world_end is not None and blur:
                b.set_camera_motion(c.to_world_end.tolist())
            b.set_filter(c.rfilter, c.stddev, c.sample_border)
            self._compiled = b.build()
        return self._compiled

    @property
    def ray_tracer(self) -> str:
        """What traces the scene's triangle meshes: ``"embree 3.13.5"``
        (Intel Embree 3, the kernels Mitsuba 3 traces with, loaded at run
        time when ``libembree3.so.3`` is installed: Debian's
        ``libembree3-3``) or ``"obvhs"`` (mcsample's own BVH, always
        there). The environment variable ``MCSAMPLE_RAY_TRACER`` chooses
        when the scene is first used: ``"embree"`` (a ``ValueError`` if
        it cannot be loaded), ``"obvhs"``, or ``"auto"`` / unset (Embree
        when it loads). Spheres and disks are always traced by obvhs."""
        return self.compiled.ray_tracer

    def sample_emitter(self, x: Any, u: Any) -> "EmitterSample":
        """Emitter sampling as the renderer's next-event estimation does it
        under ``strategy="emitter"`` (under MIS an environment map is drawn
        by its compensated density instead: see :func:`mcsample.render`).

        Parameters
        ----------
        x : array_like, shape (N, 3) or (3,)
            Points the light is sampled from (world space).
        u : array_like, shape (N, 3) or (3,), in [0, 1]
            Uniform numbers: the light's choice (by power), then two for the
            point on it (uniform by area; a sphere seen from outside: uniform
            in the cone it subtends) or the environment direction.

        Returns
        -------
        EmitterSample
            ``.direction`` (N, 3) unit vectors toward the light, ``.pdf``
            (N,) per steradian (the light's choice included), ``.radiance``
            (N, 3) arriving along it (no visibility test), ``.distance``
            (N,) to the light point (inf for the environment), ``.weight``
            = radiance / pdf; all 0 where a sample carries no light (a point
            on the back of a one-sided light).
        """
        out = np.asarray(self.compiled.sample_emitter(x, u))
        return EmitterSample(out[..., :3], out[..., 3], out[..., 4:7], out[..., 7])

    def sample_sensor(self, x: Any, u: Any) -> "SensorSample":
        """The camera seen from points ``x``, as light tracing connects to
        it (Mitsuba's ``sensor.sample_direction``): ``x`` (N, 3) or (3,) in
        world space, ``u`` (N, 2) or (2,) uniform in [0, 1] placing the
        point on a thin lens's aperture (concentric disk; a pinhole ignores
        it). The camera stands where it is at shutter_open.

        Returns a :class:`mcsample.results.SensorSample`: ``.pixel`` (N, 2),
        ``.direction`` (N, 3) toward the lens point, ``.distance``, ``.pdf``
        and ``.weight`` (N,); 0 where ``x`` is outside the clip range or its
        ray misses the film. The value a point of outgoing radiance ``L``
        adds to its pixel's mean is ``L · weight · W · H`` over the number of
        points drawn per unit area (times the cosine at the point), for a
        film of W × H pixels and its box filter.
        """
        out = np.asarray(self.compiled.sample_sensor(x, u))
        return SensorSample(out[..., :2], out[..., 2:5], out[..., 5], out[..., 6], out[..., 7])

    def emitter_pdf(self, x: Any, d: Any) -> Any:
        """The density per steradian with which :meth:`sample_emitter` from
        points ``x`` (N, 3) or (3,) draws the unit directions ``d`` (N, 3) or
        (3,): float64 (N,) or a scalar. An area light counts where ``d``
        first meets its front side (other shapes do not block it: this is
        the sampler's density, not visibility)."""
        return self.compiled.emitter_pdf(x, d)

    def integrator_settings(self, integrator: str | None = None, max_depth: int | None = None,
                            rr_depth: int | None = None,
                            hide_emitters: bool | None = None) -> dict[str, Any]:
        """The integrator's settings for a render: each argument that is
        None takes the scene dict's value, else the default (``path``,
        ``max_depth`` -1, ``rr_depth`` 5, ``hide_emitters`` False)."""
        d = self.integrator
        return {
            "integrator": integrator if integrator is not None else d.get("integrator", "path"),
            "max_depth": max_depth if max_depth is not None else d.get("max_depth", -1),
            "rr_depth": rr_depth if rr_depth is not None else d.get("rr_depth", 5),
            "hide_emitters": bool(hide_emitters if hide_emitters is not None
                                  else d.get("hide_emitters", False)),
        }

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)`` of the film in pixels, as numpy's shapes."""
        return self.camera.height, self.camera.width

    def to_mitsuba(self, spp: int | None = None,
                   latlong_width: int | None = None) -> dict[str, Any]:
        """A dict for ``mi.load_dict`` that renders this scene in Mitsuba 3
        (a Mitsuba variant must be set; see
        :func:`mcsample.mitsuba.scene_dict`)."""
        from ..mitsuba.export import scene_dict

        return scene_dict(self, spp=spp, latlong_width=latlong_width)

    def copy(self) -> "Scene":
        """A deep copy (change it and render again)."""
        return copy.deepcopy(self)
