"""Estimators of irradiance and reflected radiance under an environment map."""

from typing import Final, Literal, final

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

def irradiance(env: EnvMap, normal: ArrayLike, n: int, *, strategy: _Strategy = "mis",
               seed: int | np.random.Generator | None = 0,
               heuristic: Literal["balance", "power"] = "power") -> Estimate: ...
def reflected_radiance(env: EnvMap, phong: Phong, normal: ArrayLike, wi: ArrayLike, n: int, *,
                       strategy: _Strategy = "mis", seed: int | np.random.Generator | None = 0,
                       heuristic: Literal["balance", "power"] = "power") -> Estimate: ...
