"""mcsample: the Monte Carlo sampling toolkit of a physically based renderer.

Random numbers (PCG32), warps, distributions and the statistics that prove
them right, computed in Rust on all cores and checked against Mitsuba 3.
Conventions (sample-major batches, float32 in / float32 out, densities per
steradian on directions, +z normal) are in the README.
"""

from . import io, stats, warp
from ._core import Rng, __version__, get_num_threads, set_num_threads, uniform

__all__ = [
    "Rng",
    "__version__",
    "get_num_threads",
    "io",
    "set_num_threads",
    "stats",
    "uniform",
    "warp",
]
