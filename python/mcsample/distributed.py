"""``mcsample.distributed``: renders (and estimator runs) split into chunks
of samples and run on a Dask cluster (``dask.distributed``, an optional dependency: ``pip install
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
import os
import time
from typing import TYPE_CHECKING, Any, Callable, Iterator, Sequence

from ._args import integer
from ._core import get_num_threads, set_num_threads
from .rendering import _progress_bar
from .rendering import render as _render_local
from ._core.estimators import Estimate
from .results import RenderResult
from .scene import Scene
from .seeds import SeedLike, resolve_seed

if TYPE_CHECKING:
    from distributed import Client

__all__ = ["chunk_sizes", "estimate", "render"]


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


def _use_worker_threads(caller: int) -> None:
    """On a Dask worker in a process of its own (not that of ``caller``, the
    process that submitted the chunk), mcsample's threads are the worker's
    (the count is per process: an in-process worker leaves it alone)."""
    if os.getpid() == caller:
        return
    with contextlib.suppress(ValueError, ImportError):
        from distributed import get_worker

        threads = get_worker().state.nthreads
        if get_num_threads() != threads:
            set_num_threads(threads)


def _render_chunk(scene: Scene, spp: int, first_sample: int, kw: dict[str, Any],
                  caller: int) -> RenderResult:
    """One chunk of a render, on a worker."""
    _use_worker_threads(caller)
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
        keeps its sums (``first_sample=0``): an independent render can be
        continued by merging more samples into it.

    Ctrl-C cancels the chunks that are not done and raises
    KeyboardInterrupt.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be an mcsample.Scene, got {type(scene).__name__}")
    _refuse_chunk_options(kw, "first_sample", "total_spp")
    spp = integer(spp, "spp", 1)
    kw = {**kw, "seed": resolve_seed(seed), "total_spp": spp}
    start = time.perf_counter()
    count, sizes = _chunking(chunks, spp, "samples")
    with _client(client) as c:
        if sizes is None:
            sizes = chunk_sizes(spp, count or _default_count(c))
        height, width = scene.shape
        merged = _run(c, scene, _render_chunk, sizes, kw, width * height, progress,
                      lambda r: r.spp, RenderResult.merge)
    return RenderResult(merged.image, merged.variance, merged.luminance_variance, merged.spp,
                        time.perf_counter() - start, 0, merged.chunk)


def estimate(estimator: Callable[..., Estimate], *args: Any, n: int,
             client: Client | None = None, chunks: int | Sequence[int] | None = None,
             seed: SeedLike = 0, progress: bool = True, **kw: Any) -> Estimate:
    """Runs ``estimator(*args, n=n, **kw)`` (``mcsample.estimators.irradiance``
    or ``reflected_radiance``) in chunks of evaluations on a Dask cluster.

    Parameters
    ----------
    estimator : callable
        ``mcsample.estimators.irradiance`` or ``reflected_radiance``.
    *args
        Its positional arguments before ``n`` (``env, normal`` or ``env,
        phong, normal, wi``), sent once to every worker.
    n : int
        Evaluations in all.
    client, progress
        As :func:`render`.
    chunks : int or sequence of int, optional
        The number of chunks, or the evaluations of each (all but the last
        multiples of 16384, adding up to ``n``). Default: four per worker
        thread, each a multiple of 16384.
    seed : int, None or numpy.random.Generator
        As the estimator's; None draws one seed here, for every chunk.
    **kw
        The estimator's other options (``strategy``, ``sampler``, ...).

    Returns
    -------
    Estimate
        The bits of ``estimator(*args, n, seed=seed, **kw)``, keeping its
        partial sums (``Estimate.merge`` takes it).
    """
    _refuse_chunk_options(kw, "first_sample", "total_n")
    n = integer(n, "n", 1)
    kw = {**kw, "seed": resolve_seed(seed), "total_n": n}
    count, sizes = _chunking(chunks, n, "evaluations")
    if sizes is not None and any(k % _PART for k in sizes[:-1]):
        raise ValueError(f"chunks = {sizes}: all but the last must be multiples of "
                         f"{_PART} (the evaluations of a partial sum)")
    with _client(client) as c:
        if sizes is None:
            size = _PART * max(1, math.ceil(n / (count or _default_count(c)) / _PART))
            sizes = [size] * (n // size) + ([n % size] if n % size else [])
        return _run(c, (estimator, args), _estimate_chunk, sizes, kw, 1, progress,
                    lambda e: e.n, Estimate.merge)


#: Evaluations per partial sum of an estimate (chunks start at multiples).
_PART = 16384


def _estimate_chunk(job: tuple[Callable[..., Estimate], tuple[Any, ...]], n: int,
                    first_sample: int, kw: dict[str, Any], caller: int) -> Estimate:
    """One chunk of an estimate, on a worker."""
    _use_worker_threads(caller)
    estimator, args = job
    return estimator(*args, n=n, first_sample=first_sample, **kw)


def _refuse_chunk_options(kw: dict[str, Any], *names: str) -> None:
    """TypeError for options that the chunking chooses."""
    for name in names:
        if name in kw:
            raise TypeError(f"{name} is chosen per chunk by mcsample.distributed")


def _default_count(c: Client) -> int:
    """Four chunks per thread of the cluster."""
    return 4 * (sum(c.nthreads().values()) or 1)


def _chunking(chunks: int | Sequence[int] | None, total: int,
              what: str) -> tuple[int | None, list[int] | None]:
    """``chunks`` checked (before a cluster is started): a count, or the
    sizes (positive, adding up to ``total``), or neither (the default)."""
    if chunks is None:
        return None, None
    if isinstance(chunks, int):
        return integer(chunks, "chunks", 1), None
    sizes = [integer(k, "chunks", 1) for k in chunks]
    if sum(sizes) != total:
        raise ValueError(f"chunks add up to {sum(sizes)} {what}: they must add up to {total}")
    return None, sizes


def _run(c: Client, shared: Any, task: Callable[..., Any], sizes: list[int],
         kw: dict[str, Any], scale: int, progress: bool, count: Callable[[Any], int],
         merge: Callable[[list[Any]], Any]) -> Any:
    """Sends ``shared`` to every worker once, runs ``task(shared, size,
    first, kw, this process's id)`` for each chunk, and merges the results as they arrive;
    Ctrl-C (or any error) cancels what is left."""
    firsts = [sum(sizes[:i]) for i in range(len(sizes))]
    [remote] = c.scatter([shared], broadcast=True)
    futures = [c.submit(task, remote, n, k, kw, os.getpid(), pure=False)
               for n, k in zip(sizes, firsts)]
    callback, bar = _progress_bar(sum(sizes) * scale, progress)
    try:
        return _merge_as_completed(futures, callback, scale, count, merge)
    except BaseException:
        c.cancel([remote, *futures])
        raise
    finally:
        if bar is not None:
            bar.close()


def _merge_as_completed(futures: list[Any], callback: Any, scale: int,
                        count: Callable[[Any], int], merge: Callable[[list[Any]], Any]) -> Any:
    """Merges the chunks in order as they arrive (a chunk that comes early
    waits for those before it); ``count`` is a result's number of samples,
    ``scale`` the progress units per sample."""
    from distributed import as_completed

    waiting: dict[int, Any] = {}
    merged: Any = None
    done = 0
    for future in as_completed(futures):
        chunk = future.result()
        future.release()
        waiting[chunk.first_sample] = chunk
        done += count(chunk)
        if callback is not None:
            callback(done * scale)
        next_sample = 0 if merged is None else count(merged)
        while next_sample in waiting:
            part = waiting.pop(next_sample)
            merged = part if merged is None else merge([merged, part])
            next_sample = count(merged)
    assert merged is not None and not waiting
    return merged
