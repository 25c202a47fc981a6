"""Reference renders of an :class:`mcsample.Scene` by Mitsuba 3."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Literal

import numpy as np

from ..results import RenderResult
from ..scene.parse import MITSUBA_SAMPLERS
from ..seeds import SeedLike, resolve_seed
from .export import scene_dict
from .variant import variant_set

if TYPE_CHECKING:
    from ..scene import Scene


def render_reference(scene: "Scene", spp: int, *, seed: SeedLike = 0,
                     integrator: Literal["direct", "path"] | None = None,
                     max_depth: int | None = None, rr_depth: int | None = None,
                     variant: str | None = None,
                     hide_emitters: bool | None = None,
                     sampler: str | None = None) -> RenderResult:
    """Renders ``scene`` in Mitsuba 3 (``variant``: default
    :func:`choose_variant`; the caller's variant is set again afterwards)
    with its ``path`` or ``direct`` integrator
    wrapped in ``moment``, so each pixel comes with the variance of its mean
    luminance. The film uses a box filter, as mcsample's. ``integrator``,
    ``max_depth``, ``rr_depth`` and ``hide_emitters`` default to the scene
    dict's integrator, as in :func:`mcsample.render`; ``seed`` is taken as
    there (and reduced to Mitsuba's 32 bits). ``sampler`` is Mitsuba's
    sampler plugin ("independent", "stratified", "multijitter",
    "orthogonal", "ldsampler"; default: the scene dict's, else
    "independent"); the samples per pixel are the count Mitsuba's sampler
    makes of ``spp`` (some round it up), reported as ``.spp``. Everything
    after ``spp`` is keyword-only.

    Returns a :class:`mcsample.RenderResult` whose ``variance`` is None
    (Mitsuba reports moments in XYZ, from which per-RGB-channel variances
    cannot be recovered) and whose ``luminance_variance`` is
    (E[Y²] − E[Y]²) / (spp − 1); ``seconds`` includes Mitsuba's JIT
    compilation unless its kernels are cached from an earlier call.
    """
    with variant_set(variant) as mi:
        settings = scene.integrator_settings(integrator, max_depth, rr_depth, hide_emitters)
        kind = settings["integrator"]
        if kind not in ("path", "direct"):
            raise ValueError(f"integrator = {kind!r}: must be 'path' or 'direct'")
        nested: dict = {"type": kind, "hide_emitters": settings["hide_emitters"]}
        if kind == "path":
            nested["max_depth"] = int(settings["max_depth"])
            nested["rr_depth"] = int(settings["rr_depth"])
        d = scene_dict(scene, spp=spp)
        if sampler is not None:
            if sampler not in MITSUBA_SAMPLERS:
                raise ValueError(f"sampler = {sampler!r}: must be one of "
                                 f"{', '.join(map(repr, MITSUBA_SAMPLERS))}")
            d["sensor"]["sampler"]["type"] = sampler
        d["integrator"] = {"type": "moment", "nested": nested}
        mi_scene = mi.load_dict(d)
        # Mitsuba rounds some samplers' counts up (stratified: to a square,
        # orthogonal: to a prime squared, ldsampler: to a power of two).
        spp = int(mi_scene.sensors()[0].sampler().sample_count())
        start = time.perf_counter()
        out = np.asarray(mi.render(mi_scene, spp=spp, seed=resolve_seed(seed) % 2**32),
                         dtype=np.float64)
        seconds = time.perf_counter() - start
    # Channels: R, G, B, nested.X, Y, Z, m2_nested.X, Y, Z.
    m1, m2 = out[..., 4], out[..., 7]
    var = np.maximum(m2 - m1 * m1, 0.0) / max(spp - 1, 1)
    return RenderResult(out[..., :3].astype(np.float32), None, var.astype(np.float32),
                        spp, seconds)
