"""``mcsample.render``: the compact renderer, driven from Python.

The work runs in Rust on all cores with the GIL released; a progress bar
(tqdm: in a terminal or a notebook) appears for renders longer than a second,
and Ctrl-C stops a render within about a tenth of a second, raising
KeyboardInterrupt.
"""

from __future__ import annotations

import time
import warnings
from typing import Any, Callable, Literal

from ._core.render import render as _render
from .results import Chunk, RenderResult, StrategyImage
from .estimators import Sampler
from .scene import Scene
from .scene.parse import MITSUBA_SAMPLERS
from .seeds import SeedLike, resolve_seed

__all__ = ["RenderResult", "render"]


def _progress_bar(total: int, enabled: bool) -> tuple[Callable[[int], None] | None, Any]:
    if not enabled:
        return None, None
    try:
        with warnings.catch_warnings():
            # A notebook without ipywidgets: tqdm warns, then draws as text.
            warnings.simplefilter("ignore")
            from tqdm.auto import tqdm
    except ImportError:
        return None, None
    bar = tqdm(total=total, unit="spl", unit_scale=True, delay=1.0, desc="render",
               leave=False)

    def update(done: int) -> None:
        bar.update(done - bar.n)

    return update, bar


def render(scene: Scene, spp: int | None = None, *,
           integrator: Literal["direct", "path", "ptracer", "bdpt"] | None = None,
           strategy: Literal["bsdf", "emitter", "mis"] = "mis",
           heuristic: Literal["balance", "power"] = "power", max_depth: int | None = None,
           rr_depth: int | None = None, seed: SeedLike = 0, progress: bool = True,
           hide_emitters: bool | None = None, sampler: Sampler | None = None,
           first_sample: int | None = None, total_spp: int | None = None,
           strategies: bool = False) -> RenderResult:
    """Renders ``scene`` with ``spp`` samples per pixel.

    Parameters
    ----------
    scene : Scene
        From :meth:`mcsample.Scene.from_mitsuba`.
    spp : int, optional
        Samples per pixel (default: the scene's sampler ``sample_count``, else 16).
    integrator : "direct", "path", "ptracer" or "bdpt", optional
        Direct illumination (emitted + direct light), path tracing with
        next-event estimation and Russian roulette, or light tracing (as
        Mitsuba's ``ptracer``: ``spp`` × H × W paths start on the lights,
        each vertex is connected to the camera and splatted onto the film
        with the scene's filter, normalised as Mitsuba's; lights seen
        directly are connected to the camera from a point drawn on them;
        the variance of each pixel comes from its value on every path).
        "bdpt" is bidirectional path tracing (Veach; as pbrt-v4's): per
        sample a camera subpath and a light subpath, joined in every way
        (s light vertices, t camera vertices: the camera path hitting a
        light, next-event estimation, light tracing's connection to the
        camera, and every other join), weighted by ``heuristic`` over all
        the ways; its light connections and camera samples are splatted
        alike (with the Gaussian filter, the normalised splat of
        "ptracer"), and each pixel's variance comes from its per-sample
        totals. Under "ptracer" and "bdpt" a light path reaches several
        pixels, so neighbouring pixels' errors are slightly correlated: a
        region's variance taken as the sum of its pixels' understates it a
        little (measured within about 20 %). ``strategy`` does not apply to
        "ptracer" and "bdpt".
        Default: the scene dict's integrator, else "path".
    strategy : "bsdf", "emitter" or "mis"
        How light is found: BSDF sampling, emitter sampling (envmap
        importance sampling; area lights uniformly by area, converted to
        solid angle; lights chosen by power), or MIS of the two. Under MIS
        an environment map is drawn by its compensated density (as
        ``EnvMap(..., compensate=True)``: luminance less its mean, clamped
        at 0; MIS compensation, as pbrt-v4 samples image lights under MIS),
        which leaves its dark parts to BSDF sampling (an estimate with the
        same mean and about 1.3 times less variance on the demo scene);
        emitter sampling alone, "ptracer" and "bdpt" draw it by its own
        density.
    heuristic : "balance" or "power"
        The MIS weight (power: exponent 2, as Mitsuba).
    max_depth : int, optional
        Longest path in segments, as Mitsuba's (1: emission only, 2: direct
        light, -1: unbounded, the default). Only for "path".
    rr_depth : int, optional
        Depth from which Russian roulette may end a path (default 5): the
        survival probability is min(max(throughput), 0.95).
    seed : int, None or numpy.random.Generator
        The same seed gives the same image whatever the thread count; None
        draws a fresh seed from the operating system, a Generator draws one
        from itself.
    progress : bool
        Show a progress bar for renders that take longer than a second.
    hide_emitters : bool, optional
        Leave out emitters seen straight from the camera (area lights and
        the environment), as Mitsuba's ``hide_emitters``. Default: the
        scene dict's integrator, else False.
    sampler : "independent", "stratified", "multijitter", "sobol", "ldsampler" or "zsobol", optional
        Where each pixel's uniform numbers come from. Default: the scene
        dict's sensor sampler (Mitsuba's ``stratified``, ``multijitter``,
        ``orthogonal`` (as "multijitter") and ``ldsampler``),
        else "independent": PCG32 numbers, a generator for each sample
        (seeded by its pixel and its index in the pixel's sequence).
        "stratified" and "multijitter" jitter the strata of a grid (Mitsuba's
        samplers of those names); "sobol" is padded Owen-scrambled Sobol'
        (pbrt-v4's PaddedSobolSampler: each request a (0, m, 2)-net of the
        first two Sobol' dimensions, its index shuffled, scrambled per pixel
        and dimension); "ldsampler" is the same shuffled nets randomised by a
        random XOR of their bits (a digital shift) instead of Owen's scramble,
        as Mitsuba's ``ldsampler`` (Kollig and Keller's scrambled
        (0, 2)-sequence); "zsobol" is pbrt-v4's z-ordered Sobol' (the same
        nets, ordered along a Morton curve over the screen: blue-noise
        error; best with power-of-two spp).
        Every random decision has its own dimension, in this order: film
        position (2), lens (2), time (1, drawn only when something moves), then per shading point
        BSDF lobe (1), BSDF direction (2, stratified as a pair), light
        choice (1; under the direct and path integrators the samplers other
        than "independent" draw it only when the scene has more than one
        light), light position (2), Russian roulette (1).
        Under these samplers a pixel's samples are not independent, and
        ``variance`` (that of independent samples) usually overstates the
        error. The nets and blocks above are whole for power-of-two spp.

    first_sample : int, optional
        Render samples ``first_sample .. first_sample + spp - 1`` of each
        pixel's sequence: a chunk of a larger render. The result keeps the
        sums :meth:`RenderResult.merge` needs (8 float64 per pixel for each
        power-of-two block of samples the chunk holds: one block when
        ``spp`` is a power of two and ``first_sample`` a multiple of it), and
        the merge of chunks covering samples ``0 .. S-1`` has the same bits
        as one render of ``S`` spp with the same seed and settings.
    total_spp : int, optional
        Length of the sequence the chunk is part of (default
        ``first_sample + spp``): the "stratified", "multijitter", "sobol", "ldsampler"
        and "zsobol" samplers lay their patterns over it, so the chunks of
        one render must all give it (the independent sampler ignores it: an
        independent render can be continued with more samples).

    strategies : bool
        With ``integrator="bdpt"`` and a ``max_depth`` in [1, 64]: also
        render the image of each strategy (s, t) (s light vertices, t camera
        vertices; path length s + t - 1 segments), weighted by its MIS weight
        (the render is their sum) and unweighted (each an estimate, on its
        own, of the light carried by paths of that length), as pbrt-v4's
        "visualize strategies": ``.strategies`` of the result,
        :func:`mcsample.plot.strategies` draws them.

    Everything after ``spp`` is keyword-only.

    Returns
    -------
    RenderResult with ``.image`` and ``.variance`` (H, W, 3) float32,
    ``.luminance_variance`` (H, W), ``.spp``, ``.seconds``, ``.first_sample``
    and, for a render given ``first_sample``, ``.chunk`` (its sums).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be an mcsample.Scene, got {type(scene).__name__}")
    settings = scene.integrator_settings(integrator, max_depth, rr_depth, hide_emitters)
    spp = scene.camera.sample_count or 16 if spp is None else spp
    if sampler is None:
        sampler = MITSUBA_SAMPLERS[scene.camera.sampler][1]  # type: ignore[assignment]
    height, width = scene.shape
    callback, bar = _progress_bar(width * height * max(int(spp), 1), progress)
    seed = resolve_seed(seed)
    start = time.perf_counter()
    try:
        image, variance, lum_var, blocks, sums = _render(
            scene.compiled, spp, seed, settings["integrator"], strategy, heuristic,
            settings["max_depth"], settings["rr_depth"], settings["hide_emitters"], callback,
            sampler, first_sample, total_spp, first_sample is not None, strategies)
    finally:
        if bar is not None:
            bar.close()
    seconds = time.perf_counter() - start
    first = blocks[0][0] if blocks else 0
    chunk = None
    if sums is not None:
        # The sequence length matters to the samplers that lay patterns over
        # it: an independent render can be continued with more samples.
        total = None if sampler == "independent" else first + int(spp) \
            if total_spp is None else int(total_spp)
        strategy_name = "emitter" if strategy == "envmap" else strategy
        chunk = Chunk(blocks, sums, (scene.shape, seed, sampler, total, strategy_name, heuristic,
                                     tuple(sorted(settings.items()))),
                      height * width if settings["integrator"] == "ptracer" else 1)
    # The render, then (with strategies) each strategy's two images.
    image, variance = (a.reshape(-1, height, width, 3) for a in (image, variance))
    lum_var = lum_var.reshape(-1, height, width)
    images = None
    if strategies:
        from ._core.render import bdpt_strategies

        images = {(s, t): StrategyImage(s, t, image[1 + 2 * i], image[2 + 2 * i],
                                        lum_var[1 + 2 * i], lum_var[2 + 2 * i])
                  for i, (s, t) in enumerate(bdpt_strategies(settings["max_depth"]))}
    return RenderResult(image[0], variance[0], lum_var[0], int(spp), seconds, first, chunk,
                        strategies=images)
