"""``mcsample.render``: the compact renderer, driven from Python.

The work runs in Rust on all cores with the GIL released; a progress bar
(tqdm: in a terminal or a notebook) appears for renders longer than a second,
and Ctrl-C stops a render within about a tenth of a second, raising
KeyboardInterrupt.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ._core.render import render as _render
from .scene import Scene
from .stats import luminance

__all__ = ["RenderResult", "render"]


@dataclass
class RenderResult:
    """A rendered image.

    Attributes
    ----------
    image : ndarray (H, W, 3) float32
        Mean radiance per pixel (linear RGB, row 0 at the top).
    variance : ndarray (H, W, 3) float32, or None
        Variance of each pixel's mean (sample variance / spp; inf for
        spp = 1). None for Mitsuba references, whose moments come in XYZ.
    luminance_variance : ndarray (H, W) float32
        Variance of each pixel's mean luminance (Rec. 709 Y), the quantity
        compared with Mitsuba (whose moment integrator reports it).
    spp : int
        Samples per pixel.
    seconds : float
        Wall-clock time of the render.
    """

    image: np.ndarray
    variance: np.ndarray | None
    luminance_variance: np.ndarray
    spp: int
    seconds: float

    @property
    def luminance(self) -> np.ndarray:
        """Rec. 709 luminance of :attr:`image`, (H, W)."""
        return luminance(self.image)


def _progress_bar(total: int, enabled: bool) -> tuple[Callable[[int], None] | None, Any]:
    if not enabled:
        return None, None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None, None
    bar = tqdm(total=total, unit="spl", unit_scale=True, delay=1.0, desc="render",
               leave=False)

    def update(done: int) -> None:
        bar.update(done - bar.n)

    return update, bar


def render(scene: Scene, spp: int | None = None, integrator: str | None = None,
           strategy: str = "mis", heuristic: str = "power", max_depth: int | None = None,
           rr_depth: int | None = None, seed: int = 0, progress: bool = True,
           hide_emitters: bool | None = None) -> RenderResult:
    """Renders ``scene`` with ``spp`` samples per pixel.

    Parameters
    ----------
    scene : Scene
        From :meth:`mcsample.Scene.from_mitsuba`.
    spp : int, optional
        Samples per pixel (default: the scene's sampler ``sample_count``, else 16).
    integrator : "direct" or "path", optional
        Direct illumination (emitted + direct light), or path tracing with
        next-event estimation and Russian roulette. Default: the scene dict's
        integrator, else "path".
    strategy : "bsdf", "emitter" or "mis"
        How light is found: BSDF sampling, emitter sampling (envmap
        importance sampling; area lights uniformly by area, converted to
        solid angle; lights chosen by power), or MIS of the two.
    heuristic : "balance" or "power"
        The MIS weight (power: exponent 2, as Mitsuba).
    max_depth : int, optional
        Longest path in segments, as Mitsuba's (1: emission only, 2: direct
        light, -1: unbounded, the default). Only for "path".
    rr_depth : int, optional
        Depth from which Russian roulette may end a path (default 5): the
        survival probability is min(max(throughput), 0.95).
    seed : int
        The same seed gives the same image whatever the thread count.
    progress : bool
        Show a progress bar for renders that take longer than a second.
    hide_emitters : bool, optional
        Leave out emitters seen straight from the camera (area lights and
        the environment), as Mitsuba's ``hide_emitters``. Default: the
        scene dict's integrator, else False.

    Returns
    -------
    RenderResult with ``.image`` and ``.variance`` (H, W, 3) float32,
    ``.spp`` and ``.seconds``.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be an mcsample.Scene, got {type(scene).__name__}")
    defaults = scene.integrator
    spp = int(spp if spp is not None else scene.camera.sample_count or 16)
    integrator = integrator or defaults.get("integrator", "path")
    max_depth = int(max_depth if max_depth is not None else defaults.get("max_depth", -1))
    rr_depth = int(rr_depth if rr_depth is not None else defaults.get("rr_depth", 5))
    hide = bool(hide_emitters if hide_emitters is not None
                else defaults.get("hide_emitters", False))
    width, height = scene.size
    compiled = scene.compiled
    callback, bar = _progress_bar(width * height * max(spp, 1), progress)
    start = time.perf_counter()
    try:
        image, variance, lum_var = _render(compiled, spp, seed, integrator, strategy, heuristic,
                                  max_depth, rr_depth, hide, callback)
    finally:
        if bar is not None:
            bar.close()
    seconds = time.perf_counter() - start
    return RenderResult(image.reshape(height, width, 3), variance.reshape(height, width, 3),
                        lum_var.reshape(height, width), spp, seconds)
