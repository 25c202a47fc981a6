"""Timing: the median wall time of a call, alone, side by side with other
calls, or alternating with them."""


from __future__ import annotations

import statistics
import time
from typing import Callable, NamedTuple



class Timing(NamedTuple):
    case: str
    implementation: str
    dtype: str
    n: int
    seconds: float

    @property
    def msamples_per_s(self) -> float:
        return self.n / self.seconds / 1e6


def measure(fn: Callable[[], object], repeat: int = 7, warmup: int = 2) -> float:
    """Median wall time of ``fn()`` in seconds over ``repeat`` runs, after
    ``warmup`` runs."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


#: Seconds to wait before each timed run of a comparison, so that the other
#: runtime's worker threads have gone idle. Dr.Jit's keep a core busy for
#: some 10-50 ms after its last call: measured here, mcsample's first
#: triangle warp right after Mitsuba's took 10.6 ms, the third 4.1 ms, and
#: after a 50 ms pause 3.7-4.4 ms. Every side gets the same pause.
IDLE_PAUSE = 0.1


def measure_side_by_side(fns: list[Callable[[], object]], repeat: int = 7,
                         warmup: int = 2) -> list[float]:
    """Median wall time of each of ``fns`` in seconds, run in turn (one run
    of each per round, ``repeat`` rounds after ``warmup``, each timed run
    after a pause of ``IDLE_PAUSE``), so that a slow spell of a shared
    machine weighs on all of them alike."""
    for _ in range(warmup):
        for fn in fns:
            fn()
    times: list[list[float]] = [[] for _ in fns]
    for _ in range(repeat):
        for fn, t in zip(fns, times):
            time.sleep(IDLE_PAUSE)
            start = time.perf_counter()
            fn()
            t.append(time.perf_counter() - start)
    return [statistics.median(t) for t in times]


def measure_alternating(fns: list[Callable[[], object]], repeat: int = 7,
                        rounds: int = 3) -> list[float]:
    """Median wall time of each of ``fns`` in seconds, timed in blocks that
    alternate: each round runs every function after a pause of
    ``IDLE_PAUSE`` (so that the other runtime's worker threads have gone
    idle), once untimed and then ``repeat`` times, for ``rounds`` rounds;
    the median is over every timed run. For calls of a few milliseconds,
    where one call right after another runtime's is slowed by its spinning
    threads, yet a single block each would leave the comparison to whichever
    ran in a quiet spell."""
    times: list[list[float]] = [[] for _ in fns]
    for _ in range(rounds):
        for fn, t in zip(fns, times):
            time.sleep(IDLE_PAUSE)
            fn()
            for _ in range(repeat):
                start = time.perf_counter()
                fn()
                t.append(time.perf_counter() - start)
    return [statistics.median(t) for t in times]


def _mitsuba():
    from .. import mitsuba as mcs_mitsuba

    if not mcs_mitsuba.available() or mcs_mitsuba.choose_variant() != "llvm_ad_rgb":
        return None
    return mcs_mitsuba.load("llvm_ad_rgb")
