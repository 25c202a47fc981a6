"""Reference renders of an :class:`mcsample.Scene` by Mitsuba 3."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..results import RenderResult
from ..scene.parse import MITSUBA_SAMPLERS
from ..seeds import SeedLike, resolve_seed
from .export import scene_dict
from .variant import variant_set

if TYPE_CHECKING:
    from ..scene import Scene


#: Independent Mitsuba renders a reference under a splatting filter is made
#: of (:func:`render_reference`).
RUNS = 16


def render_reference(scene: "Scene", spp: int, *, seed: SeedLike = 0,
                     integrator: Literal["direct", "path", "ptracer"] | None = None,
                     max_depth: int | None = None, rr_depth: int | None = None,
                     variant: str | None = None,
                     hide_emitters: bool | None = None,
                     sampler: str | None = None) -> RenderResult:
    """Renders ``scene`` in Mitsuba 3 (``variant``: default
    :func:`choose_variant`; the caller's variant is set again afterwards)
    with its ``path`` or ``direct`` integrator
    wrapped in ``moment``, so each pixel comes with the variance of its mean
    luminance. The film has the scene's filter. Under a Gaussian filter
    (Mitsuba splats each sample onto several pixels and divides by the
    weights, so pixels share samples and the moments do not give a pixel's
    variance), and with its ``ptracer`` (light tracing splats every path
    anywhere on the film; ``moment`` cannot wrap it), it renders
    ``RUNS`` = 16 independent images of
    ``ceil(spp / 16)`` samples instead: their mean is the image, each
    pixel's luminance variance comes from their spread, and their
    luminances are kept as ``.runs`` for region variances
    (:func:`mcsample.stats.render_ztest`). Each run's pixels are Mitsuba's
    ratio of splatted sums, biased by O(1 / its spp): keep ``spp / 16`` at
    16 or more where the bias matters. ``integrator``,
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
    (E[Y²] − E[Y]²) / (spp − 1) for the box filter (for the Gaussian, see
    above: :func:`render_runs`); ``seconds`` includes Mitsuba's JIT
    compilation unless its kernels are cached from an earlier call.
    """
    with variant_set(variant) as mi:
        settings = scene.integrator_settings(integrator, max_depth, rr_depth, hide_emitters)
        kind = settings["integrator"]
        if kind not in ("path", "direct", "ptracer"):
            raise ValueError(f"integrator = {kind!r}: must be 'path', 'direct' or 'ptracer'")
        nested: dict = {"type": kind, "hide_emitters": settings["hide_emitters"]}
        if kind != "direct":
            nested["max_depth"] = int(settings["max_depth"])
            nested["rr_depth"] = int(settings["rr_depth"])
        runs = 1 if scene.camera.rfilter == "box" and kind != "ptracer" else RUNS
        d = scene_dict(scene, spp=-(-spp // runs))
        if sampler is not None:
            if sampler not in MITSUBA_SAMPLERS:
                raise ValueError(f"sampler = {sampler!r}: must be one of "
                                 f"{', '.join(map(repr, MITSUBA_SAMPLERS))}")
            d["sensor"]["sampler"]["type"] = sampler
        d["integrator"] = {"type": "moment", "nested": nested} if runs == 1 else nested
        mi_scene = mi.load_dict(d)
        # Mitsuba rounds some samplers' counts up (stratified: to a square,
        # orthogonal: to a prime squared, ldsampler: to a power of two).
        spp = int(mi_scene.sensors()[0].sampler().sample_count())
        if runs > 1:
            return render_runs(mi_scene, spp, runs=runs, seed=seed)
        start = time.perf_counter()
        out = np.asarray(mi.render(mi_scene, spp=spp, seed=resolve_seed(seed) % 2**32),
                         dtype=np.float64)
        seconds = time.perf_counter() - start
    # Channels: R, G, B, nested.X, Y, Z, m2_nested.X, Y, Z.
    m1, m2 = out[..., 4], out[..., 7]
    var = np.maximum(m2 - m1 * m1, 0.0) / max(spp - 1, 1)
    return RenderResult(out[..., :3].astype(np.float32), None, var.astype(np.float32),
                        spp, seconds)


def render_runs(mi_scene: Any, spp: int, *, runs: int = RUNS, seed: SeedLike = 0) -> RenderResult:
    """Mitsuba's render of a scene it loaded (``mi.load_dict`` /
    ``mi.load_file``; a variant must be set) as ``runs`` independent renders
    of ``spp`` samples (seeds derived from ``seed``): the image is their
    mean, each pixel's luminance variance their spread over ``runs``
    (unbiased whatever the filter, no moment integrator), ``.runs`` their
    luminances (R, H, W) and ``.spp`` = ``spp * runs``. Takes the scene's
    own integrator and film."""
    import mitsuba as mi

    if int(runs) < 2:
        raise ValueError(f"runs = {runs}: must be >= 2")
    if int(spp) < 1:
        raise ValueError(f"spp = {spp}: must be >= 1")
    base = resolve_seed(seed)
    start = time.perf_counter()
    images = np.stack([np.asarray(mi.render(mi_scene, spp=int(spp),
                                            seed=(base + k * 0x9E3779B9) % 2**32),
                                  dtype=np.float64)[..., :3] for k in range(int(runs))])
    seconds = time.perf_counter() - start
    y = images @ np.array([0.2126, 0.7152, 0.0722])
    return RenderResult(images.mean(axis=0).astype(np.float32), None,
                        (y.var(axis=0, ddof=1) / runs).astype(np.float32), int(spp) * int(runs),
                        seconds, runs=y.astype(np.float32))
