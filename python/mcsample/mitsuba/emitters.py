"""Mitsuba 3's ``envmap`` emitter next to an :class:`mcsample.EnvMap`: the
emitter for a map, and its ``eval``, ``pdf_direction`` and
``sample_direction`` on numpy arrays (a variant must be set)."""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

import numpy as np

from ..results import TupleResult


def envmap_dict(env: Any, latlong_width: int | None = None) -> dict[str, Any]:
    """Mitsuba's ``envmap`` emitter for ``env`` as a dict for ``mi.load_dict``
    (a variant must be set): the same image, scale, rotation and MIS
    compensation. Angular and cube maps are converted to lat-long first
    (``latlong_width`` columns, default 4x the source's resolution), since
    Mitsuba's emitter takes only that form."""
    import mitsuba as mi

    if env.mapping != "latlong":
        env = env.convert("latlong", latlong_width or 4 * np.shape(env.image)[1])
    m = np.eye(4)
    m[:3, :3] = np.asarray(env.to_world)
    return {"type": "envmap", "scale": float(env.scale),
            "bitmap": mi.Bitmap(np.ascontiguousarray(env.image, dtype=np.float32)),
            "to_world": mi.ScalarTransform4f(m.tolist()),
            "mis_compensation": bool(env.compensate)}


def envmap_emitter(env: Any, latlong_width: int | None = None) -> Any:
    """Mitsuba's ``envmap`` emitter object for ``env`` (see :func:`envmap_dict`)."""
    import mitsuba as mi

    return mi.load_dict(envmap_dict(env, latlong_width))


def _per_batch(fn: Callable[..., Any], *arrays: np.ndarray) -> list[np.ndarray]:
    """Runs ``fn`` on the transposed batches (Mitsuba's vectorised types,
    one call) or, in a scalar variant, once per row; returns the outputs
    as arrays with the batch on axis 0."""
    import mitsuba as mi

    if not str(mi.variant()).startswith("scalar"):
        outputs = fn(len(arrays[0]), *(a.T for a in arrays))
        return [np.asarray(o, dtype=np.float64).T for o in outputs]
    rows = [fn(1, *row) for row in zip(*arrays)]
    return [np.array([np.asarray(r[k], dtype=np.float64) for r in rows])
            for k in range(len(rows[0]))]


def emitter_eval(emitter: Any, d: Any) -> np.ndarray:
    """Radiance (N, 3) Mitsuba's ``emitter`` sends along world directions
    ``d`` (N, 3) toward the scene (``emitter.eval`` with si.wi = -d)."""
    import drjit as dr
    import mitsuba as mi

    def fn(n: int, d: Any) -> tuple[Any]:
        si = dr.zeros(mi.SurfaceInteraction3f, n) if n > 1 else mi.SurfaceInteraction3f()
        si.wi = -mi.Vector3f(d)
        return (emitter.eval(si),)

    return _per_batch(fn, np.atleast_2d(np.asarray(d, dtype=np.float64)))[0]


def emitter_pdf(emitter: Any, d: Any) -> np.ndarray:
    """Mitsuba's ``pdf_direction`` (N,) per steradian of world directions
    ``d`` (N, 3)."""
    import drjit as dr
    import mitsuba as mi

    def fn(n: int, d: Any) -> tuple[Any]:
        it = dr.zeros(mi.Interaction3f, n) if n > 1 else mi.Interaction3f()
        ds = dr.zeros(mi.DirectionSample3f, n) if n > 1 else mi.DirectionSample3f()
        ds.d = mi.Vector3f(d)
        return (emitter.pdf_direction(it, ds),)

    return _per_batch(fn, np.atleast_2d(np.asarray(d, dtype=np.float64)))[0].reshape(-1)


@dataclasses.dataclass(frozen=True, repr=False)
class MitsubaEmitterSample(TupleResult):
    """What Mitsuba's ``sample_direction`` returns, as arrays; unpacks as
    ``direction, pdf, weight, uv``.

    Attributes
    ----------
    direction : ndarray (N, 3)
        World directions.
    pdf : ndarray (N,)
        Density per steradian.
    weight : ndarray (N, 3)
        Radiance / pdf.
    uv : ndarray (N, 2)
        Mitsuba's lat-long coordinates of the sample.
    """

    _unpack = ("direction", "pdf", "weight", "uv")

    direction: np.ndarray
    pdf: np.ndarray
    weight: np.ndarray
    uv: np.ndarray


def emitter_sample(emitter: Any, u: Any) -> MitsubaEmitterSample:
    """Mitsuba's ``sample_direction`` for ``u`` (N, 2) in float32."""
    import drjit as dr
    import mitsuba as mi

    def fn(n: int, u: Any) -> tuple[Any, Any, Any, Any]:
        it = dr.zeros(mi.Interaction3f, n) if n > 1 else mi.Interaction3f()
        ds, weight = emitter.sample_direction(it, mi.Point2f(u))
        return ds.d, ds.pdf, weight, ds.uv

    d, pdf, weight, uv = _per_batch(fn, np.atleast_2d(np.asarray(u, dtype=np.float32)))
    return MitsubaEmitterSample(d, pdf.reshape(-1), weight, uv)
