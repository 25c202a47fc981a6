"""``mcsample.distributed``: renders split into chunks of samples and run on
a Dask cluster (``dask.distributed``, an optional dependency: ``pip install
"dask[distributed]"``).

Each chunk is ``mcsample.render(scene, n, first_sample=k, total_spp=spp,
...)`` on a worker; the chunks are merged as they arrive
(:meth:`mcsample.RenderResult.merge`), so the result has the bits of one
local render of ``spp`` samples with the same seed, however many workers
ran it, in whatever order, and whether or not a worker was lost on the way
(Dask recomputes what a lost worker held, and a chunk's samples depend only
on the seed and its sample indices).
"""

from __future__ import annotations

import contextlib
import math
import time
from typing import TYPE_CHECKING, Any, Iterator, Sequence

from ._args import integer
from ._core import get_num_threads, set_num_threads
from .rendering import _progress_bar
from .rendering import render as _render_local
from .results import RenderResult
from .scene import Scene
from .seeds import SeedLike, resolve_seed

if TYPE_CHECKING:
    from distributed import Client

__all__ = ["chunk_sizes", "render"]


def chunk_sizes(spp: int, chunks: int) -> list[int]:
    """Sizes of about ``chunks`` chunks of ``spp`` samples: powers of two,
    each starting at a multiple of its size, so that each chunk keeps one
    block of sums (8 float64 per pixel) and the merges stay cheap.

    >>> chunk_sizes(100, 4)
    [32, 32, 32, 4]
    """
    if spp < 1 or chunks < 1:
        raise ValueError(f"spp = {spp} and chunks = {chunks}: both must be at least 1")
    size = 1 << max(0, math.ceil(math.log2(spp / chunks)))
    sizes = [size] * (spp // size)
    rest = spp - size * len(sizes)
    # The rest by its binary digits, largest first: each a block too.
    sizes += [1 << b for b in reversed(range(rest.bit_length())) if rest >> b & 1]
    return sizes


def _render_chunk(scene: Scene, spp: int, first_sample: int, kw: dict[str, Any]) -> RenderResult:
    """One chunk, on a worker: mcsample's threads are the worker's."""
    with contextlib.suppress(ValueError, ImportError):
        from distributed import get_worker

        threads = get_worker().state.nthreads
        if get_num_threads() != threads:
            set_num_threads(threads)
    return _render_local(scene, spp, first_sample=first_sample, progress=False, **kw)


@contextlib.contextmanager
def _client(client: Client | None) -> Iterator[Client]:
    """``client``, or a LocalCluster's for the duration."""
    try:
        from distributed import Client, LocalCluster
    except ImportError as e:
        raise ImportError(
            "mcsample.distributed needs Dask's distributed scheduler: "
            'pip install "dask[distributed]"') from e
    if client is not None:
        yield client
        return
    with LocalCluster(processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as local:
        yield local


def render(scene: Scene, spp: int, client: Client | None = None,
           chunks: int | Sequence[int] | None = None, *, seed: SeedLike = 0,
           progress: bool = True, **kw: Any) -> RenderResult:
    """Renders ``scene`` with ``spp`` samples per pixel on a Dask cluster.

    Parameters
    ----------
    scene : Scene
        Sent once to every worker (``client.scatter``).
    spp : int
        Samples per pixel of the whole render.
    client : distributed.Client, optional
        The cluster to run on. Default: a ``LocalCluster`` of this machine
        (one worker process per few cores), started for this call and
        closed after it.
    chunks : int or sequence of int, optional
        The number of chunks (split by :func:`chunk_sizes`), or the samples
        of each chunk in order (they must add up to ``spp``). Default: four
        chunks per worker thread.
    seed : int, None or numpy.random.Generator
        As :func:`mcsample.render`; None draws one seed here, for every
        chunk.
    progress : bool
        A progress bar over the samples done.
    **kw
        The other options of :func:`mcsample.render` (``integrator``,
        ``strategy``, ``sampler``, ...), the same for every chunk.

    Returns
    -------
    RenderResult
        The bits of ``mcsample.render(scene, spp, seed=seed, **kw)``;
        ``seconds`` is the wall-clock time of this call, and the result
        keeps its sums (``first_sample=0``), so more samples can be merged
        into it later.

    Ctrl-C cancels the chunks that are not done and raises
    KeyboardInterrupt.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be an mcsample.Scene, got {type(scene).__name__}")
    for name in ("first_sample", "total_spp"):
        if name in kw:
            raise TypeError(f"{name} is chosen per chunk by mcsample.distributed.render")
    spp = integer(spp, "spp", 1)
    kw = {**kw, "seed": resolve_seed(seed), "total_spp": spp}
    start = time.perf_counter()
    with _client(client) as c:
        if chunks is None or isinstance(chunks, int):
            threads = sum(c.nthreads().values()) or 1
            count = 4 * threads if chunks is None else integer(chunks, "chunks", 1)
            sizes = chunk_sizes(spp, count)
        else:
            sizes = [integer(n, "chunks", 1) for n in chunks]
            if sum(sizes) != spp:
                raise ValueError(f"chunks add up to {sum(sizes)} samples: they must add up to "
                                 f"spp = {spp}")
        firsts = [sum(sizes[:i]) for i in range(len(sizes))]
        [remote] = c.scatter([scene], broadcast=True)
        futures = [c.submit(_render_chunk, remote, n, k, kw, pure=False)
                   for n, k in zip(sizes, firsts)]
        height, width = scene.shape
        callback, bar = _progress_bar(spp * width * height, progress)
        try:
            merged = _merge_as_completed(futures, callback, width * height)
        except BaseException:
            c.cancel([remote, *futures])
            raise
        finally:
            if bar is not None:
                bar.close()
    return RenderResult(merged.image, merged.variance, merged.luminance_variance, merged.spp,
                        time.perf_counter() - start, 0, merged.chunk)


def _merge_as_completed(futures: list[Any], callback: Any, pixels: int) -> RenderResult:
    """Merges the chunks in sample order as they arrive (a chunk that comes
    early waits for those before it)."""
    from distributed import as_completed

    waiting: dict[int, RenderResult] = {}
    merged: RenderResult | None = None
    done = 0
    for future in as_completed(futures):
        chunk: RenderResult = future.result()
        future.release()
        waiting[chunk.first_sample] = chunk
        done += chunk.spp
        if callback is not None:
            callback(done * pixels)
        next_sample = 0 if merged is None else merged.spp
        while next_sample in waiting:
            part = waiting.pop(next_sample)
            merged = part if merged is None else RenderResult.merge([merged, part])
            next_sample = merged.spp
    assert merged is not None and not waiting
    return merged

