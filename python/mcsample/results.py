"""mcsample's result objects, one family: attributes by name, a short repr
(arrays shown by shape and dtype, never dumped), and, where a result took
the place of a tuple, unpacking in the tuple's order (``x, pdf =
pc.sample(u)``: :class:`TupleResult`). This module imports nothing from
the rest of mcsample.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Iterable, Iterator

import numpy as np

__all__ = ["Chunk", "EmitterSample", "RenderResult", "Result", "SensorSample", "StrategyImage",
           "TupleResult", "describe"]


def describe(value: Any) -> str:
    """A short text for a value in a repr: arrays by shape and dtype, floats
    to 4 significant digits, long lists by length."""
    if isinstance(value, np.ndarray):
        if value.ndim == 0:
            return describe(value.item())
        return f"array({value.shape}, {value.dtype})"
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.4g}"
    if isinstance(value, (list, tuple)) and len(value) > 4:
        return f"[{len(value)} items]"
    return repr(value)


class Result:
    """Base of the result dataclasses: a short repr of their fields.
    ``_hidden`` lists the fields the repr leaves out (long messages, back
    references)."""

    _hidden: tuple[str, ...] = ()

    def __repr__(self) -> str:
        fields = [f.name for f in dataclasses.fields(self)]  # type: ignore[arg-type]
        shown = [f"{name}={describe(getattr(self, name))}" for name in fields
                 if name not in self._hidden and not name.startswith("_")]
        return f"{type(self).__name__}({', '.join(shown)})"


class TupleResult(Result):
    """A result that took the place of a tuple: it unpacks, indexes and has
    the length of that tuple, whose fields ``_unpack`` lists in order."""

    _unpack: tuple[str, ...] = ()

    def _tuple(self) -> tuple[Any, ...]:
        return tuple(getattr(self, name) for name in self._unpack)

    def __iter__(self) -> Iterator[Any]:
        return iter(self._tuple())

    def __getitem__(self, index: int) -> Any:
        return self._tuple()[index]

    def __len__(self) -> int:
        return len(self._unpack)


@dataclasses.dataclass(frozen=True, repr=False)
class Chunk(Result):
    """What :meth:`RenderResult.merge` needs of a chunk of a render.

    Attributes
    ----------
    blocks : list of (int, int)
        The chunk's samples as blocks ``(start, length)``: lengths are
        powers of two, each start a multiple of its length; the pixel sums
        are kept per block so that merges add them in one fixed order.
    sums : ndarray (H * W * len(blocks) * 8,) float64
        Per pixel and block: the sums of R, G, B, their squares, the
        luminance and its square.
    key : tuple
        Shape, seed, sampler, sequence length and settings of the render.
    paths_per_sample : int
        The paths each sample index holds for a pixel's estimate: 1, or the
        film's pixels for light tracing (one light path per pixel).
    """

    blocks: list[tuple[int, int]]
    sums: np.ndarray
    key: tuple[Any, ...]
    paths_per_sample: int = 1


@dataclasses.dataclass(repr=False)
class RenderResult(Result):
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
        Wall-clock time of the render (of every chunk, for a merge).
    first_sample : int
        Index of the first sample in each pixel's sequence (0 unless
        rendered with ``first_sample=``).
    chunk : Chunk or None
        What :meth:`merge` needs: kept by renders given ``first_sample``.
    strategies : dict or None
        For a bidirectional render given ``strategies=True``: each strategy
        ``(s, t)`` → its :class:`StrategyImage`.
    runs : ndarray (R, H, W) float32, or None
        The luminances of R independent renders whose mean is ``image``,
        for a Mitsuba reference of a splatting filter (its neighbouring
        pixels share samples, so the variance of a region is taken from
        them: :func:`mcsample.stats.render_ztest`); else None.

    In a notebook, a RenderResult shows as its tone-mapped image.
    """

    image: np.ndarray
    variance: np.ndarray | None
    luminance_variance: np.ndarray
    spp: int
    seconds: float
    first_sample: int = 0
    chunk: Chunk | None = None
    runs: np.ndarray | None = None
    strategies: dict[tuple[int, int], StrategyImage] | None = None

    _hidden = ("chunk", "runs", "strategies")

    @classmethod
    def merge(cls, results: Iterable[RenderResult]) -> RenderResult:
        """The render of the samples that ``results`` cover together.

        ``results`` are chunks of one render (``mcsample.render`` with the
        same scene, seed and settings, each with ``first_sample=``), in any
        order, covering consecutive samples without gaps or overlaps. The
        merge of chunks covering samples ``0 .. S-1`` has the same bits
        (image and variances) as one render of ``S`` spp; it can be merged
        again with the chunks that follow it.

        Raises ValueError for chunks of different renders (shape, seed,
        sampler, settings, and ``total_spp`` for the samplers whose patterns
        span it: an independent render can be continued with more samples),
        with gaps or overlaps, or rendered without ``first_sample``. The
        scene itself is not compared: merge chunks of one scene.
        """
        from ._core.render import merge

        results = list(results)
        if not results:
            raise ValueError("results is empty: nothing to merge")
        for r in results:
            if not isinstance(r, RenderResult) or r.chunk is None:
                raise ValueError(
                    "results must be RenderResults of renders given first_sample= (which keep "
                    "the sums a merge needs)")
        results.sort(key=lambda r: r.first_sample)
        key = results[0].chunk.key  # type: ignore[union-attr]
        for r in results[1:]:
            if r.chunk.key != key:  # type: ignore[union-attr]
                raise ValueError(
                    "results are chunks of different renders: shape, seed, sampler, total_spp "
                    f"or settings differ ({key} and {r.chunk.key})")  # type: ignore[union-attr]
        height, width = results[0].image.shape[:2]
        per_sample = results[0].chunk.paths_per_sample  # type: ignore[union-attr]
        image, variance, lum_var, blocks, sums = merge(
            [(r.chunk.blocks, r.chunk.sums) for r in results], height * width,  # type: ignore[union-attr]
            per_sample)
        spp = sum(length for _, length in blocks)
        return cls(image.reshape(height, width, 3), variance.reshape(height, width, 3),
                   lum_var.reshape(height, width), spp, sum(r.seconds for r in results),
                   results[0].first_sample, Chunk(blocks, sums, key, per_sample))

    @property
    def luminance(self) -> np.ndarray:
        """Rec. 709 luminance of :attr:`image`, (H, W) float64."""
        return np.asarray(self.image, dtype=np.float64) @ np.array([0.2126, 0.7152, 0.0722])

    def _repr_png_(self) -> bytes:
        from ._core.io import encode_png

        return encode_png(np.ascontiguousarray(self.image, dtype=np.float32))


@dataclasses.dataclass(frozen=True, repr=False)
class StrategyImage(Result):
    """One strategy of a bidirectional render (``mcsample.render(...,
    integrator="bdpt", strategies=True)``): paths made of ``s`` light
    vertices and ``t`` camera vertices, ``s + t - 1`` segments.

    Attributes
    ----------
    s, t : int
        Light and camera vertices.
    weighted : ndarray (H, W, 3) float32
        Its contribution to the render (MIS-weighted); over the strategies
        of one path length these add up to that length's light.
    unweighted : ndarray (H, W, 3) float32
        Its estimate alone (not weighted): an unbiased image of the light
        carried by paths of ``s + t - 1`` segments, noisy where the
        strategy samples those paths poorly.
    weighted_variance, unweighted_variance : ndarray (H, W) float32
        Variance of each pixel's mean luminance.
    """

    s: int
    t: int
    weighted: np.ndarray
    unweighted: np.ndarray
    weighted_variance: np.ndarray
    unweighted_variance: np.ndarray

    @property
    def depth(self) -> int:
        """Segments of its paths, ``s + t - 1``."""
        return self.s + self.t - 1


@dataclasses.dataclass(frozen=True, repr=False)
class SensorSample(Result):
    """Connections to the camera, from :meth:`mcsample.Scene.sample_sensor`
    (as Mitsuba's ``sensor.sample_direction``).

    Attributes
    ----------
    pixel : ndarray (N, 2)
        Where the ray from the lens point through the point lands on the
        film, in pixels (x right, y down; Mitsuba's ``uv``).
    direction : ndarray (N, 3)
        Unit vectors from the point toward the lens point.
    distance : ndarray (N,)
        Distance to the lens point.
    pdf : ndarray (N,)
        Density per steradian of the lens point seen from the point (1 for
        a pinhole, a delta).
    weight : ndarray (N,)
        The importance the connection carries, ``1 / (A cos³θ d²)`` (``A``
        the image's area at distance 1, ``θ`` the ray's angle to the
        optical axis, ``d`` the distance); all fields 0 where the point is
        outside the clip range or its ray misses the film.
    """

    pixel: np.ndarray
    direction: np.ndarray
    distance: np.ndarray
    pdf: np.ndarray
    weight: np.ndarray


@dataclasses.dataclass(frozen=True, repr=False)
class EmitterSample(Result):
    """Directions toward the lights, from :meth:`mcsample.Scene.sample_emitter`.

    Attributes
    ----------
    direction : ndarray (N, 3)
        Unit vectors toward the light (0 where a sample carries no light).
    pdf : ndarray (N,)
        Density per steradian, the light's choice included.
    radiance : ndarray (N, 3)
        Radiance arriving along the direction (no visibility test).
    distance : ndarray (N,)
        Distance to the light point (inf for the environment).
    """

    direction: np.ndarray
    pdf: np.ndarray
    radiance: np.ndarray
    distance: np.ndarray

    @property
    def weight(self) -> np.ndarray:
        """radiance / pdf, 0 where pdf is 0."""
        pdf = np.asarray(self.pdf)[..., None]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(pdf > 0, self.radiance / np.where(pdf > 0, pdf, 1.0), 0.0)
