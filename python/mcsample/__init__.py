"""mcsample: the Monte Carlo sampling toolkit of a physically based renderer.

Random numbers (PCG32), warps, distributions and the statistics that prove
them right, computed in Rust on all cores and checked against Mitsuba 3.
Conventions (sample-major batches, float32 in / float32 out, densities per
steradian on directions, +z normal) are in the README.
"""

from . import data, distr, estimators, io, mis, mitsuba, plot, qmc, stats, warp
from . import distributed
from .rendering import render
from .results import EmitterSample, RenderResult, SensorSample
from .scene import Scene, look_at
from ._core import (
    EnvMap,
    EnvSample,
    Frame,
    Phong,
    PhongSample,
    PiecewiseSample,
    ReusedSample,
    Rng,
    __version__,
    get_num_threads,
    set_num_threads,
    uniform,
)
from .distr import (
    AliasTable,
    Discrete1D,
    Discrete2D,
    PiecewiseConstant1D,
    PiecewiseConstant2D,
    rejection_sample,
)

__all__ = [
    "EmitterSample",
    "EnvMap",
    "RenderResult",
    "Scene",
    "SensorSample",
    "look_at",
    "render",
    "EnvSample",
    "data",
    "AliasTable",
    "Discrete1D",
    "Discrete2D",
    "Frame",
    "PiecewiseConstant1D",
    "Phong",
    "PhongSample",
    "PiecewiseSample",
    "ReusedSample",
    "PiecewiseConstant2D",
    "Rng",
    "distr",
    "distributed",
    "estimators",
    "__version__",
    "get_num_threads",
    "io",
    "mis",
    "mitsuba",
    "plot",
    "rejection_sample",
    "set_num_threads",
    "stats",
    "uniform",
    "qmc",
    "warp",
]
