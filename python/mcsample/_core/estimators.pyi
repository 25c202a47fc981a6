"""Estimators of irradiance and reflected radiance under an environment map."""

from typing import Final, Literal, Sequence, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import EnvMap, Phong

_Strategy = Literal["uniform", "cosine", "bsdf", "emitter", "envmap", "mis"]

@final
class Estimate:
    """A Monte Carlo estimate of an RGB quantity."""

    value: Final[NDArray[np.float64]]
    stderr: Final[NDArray[np.float64]]
    n: Final[int]
    strategy: Final[str]
    first_sample: Final[int]
    mergeable: Final[bool]

    @staticmethod
    def merge(estimates: Sequence[Estimate]) -> Estimate:
        """The estimate of chunks of one run: the bits of one run."""

def estimate(env: EnvMap, normal: ArrayLike, n: int, *, phong: Phong | None = None,
             wi: ArrayLike | None = None, strategy: _Strategy,
             seed: int | np.random.Generator | None, heuristic: Literal["balance", "power"],
             sampler: Literal["independent", "stratified", "multijitter", "sobol", "ldsampler", "zsobol"],
             first_sample: int | None = None, total_n: int | None = None) -> Estimate:
    """The irradiance (without phong) or the reflected radiance (with phong
    and wi): see mcsample.estimators."""
