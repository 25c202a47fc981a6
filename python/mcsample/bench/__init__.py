"""``python -m mcsample bench``: throughput of mcsample's kernels side by
side with a vectorised numpy implementation and, when it runs here, Mitsuba
3's llvm_ad_rgb variant, in one run.

Each case is timed as the median of ``repeat`` runs after ``warmup`` runs
(which also exclude Mitsuba's JIT compilation), and reported in millions of
samples per second. Later issues add their cases to :data:`SUITES`.
"""

from __future__ import annotations

from typing import Callable

import mcsample as mcs

from .kernels import (suite_distr, suite_envmap, suite_phong, suite_qmc, suite_rng,
                      suite_warps)
from .renders import (suite_bidirectional, suite_convergence, suite_meshes, suite_render,
                      suite_samplers)
from .timing import Timing, _mitsuba, measure, measure_alternating, measure_side_by_side

__all__ = ["SUITES", "Timing", "main", "measure", "measure_alternating",
           "measure_side_by_side"]


SUITES: dict[str, Callable[[int, int, object], list[Timing]]] = {
    "rng": suite_rng,
    "warps": suite_warps,
    "distr": suite_distr,
    "phong": suite_phong,
    "envmap": suite_envmap,
    "render": suite_render,
    "convergence": suite_convergence,
    "qmc": suite_qmc,
    "samplers": suite_samplers,
    "bidirectional": suite_bidirectional,
    "meshes": suite_meshes,
}


def main(n: int = 10_000_000, repeat: int = 7, only: list[str] | None = None) -> list[Timing]:
    """Runs the suites (all, or those named in ``only``) and prints a table."""
    mi = _mitsuba()
    if mi is not None:
        import drjit as dr

        # The versions, since Mitsuba's speed changes from release to release.
        other = f"Mitsuba {mi.__version__} (Dr.Jit {dr.__version__}) llvm_ad_rgb"
    else:
        other = "Mitsuba: not available (llvm variant)"
    print(f"mcsample {mcs.__version__}, {mcs.get_num_threads()} threads, n = {n:,}; {other}")
    timings: list[Timing] = []
    for name, suite in SUITES.items():
        if only and name not in only:
            continue
        timings.extend(suite(n, repeat, mi))
    print(f"{'case':32s} {'implementation':22s} {'dtype':8s} {'median ms':>10s} {'M/s':>9s}")
    for t in timings:
        print(f"{t.case:32s} {t.implementation:22s} {t.dtype:8s} "
              f"{t.seconds * 1e3:10.2f} {t.msamples_per_s:9.1f}")
    return timings
