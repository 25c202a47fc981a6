"""Estimators of irradiance and reflected radiance under an environment map."""

from typing import Literal, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import EnvMap, Phong

_Strategy = Literal["uniform", "cosine", "bsdf", "emitter", "envmap", "mis"]

@final
class Estimate:
    """A Monte Carlo estimate of an RGB quantity."""

    @property
    def value(self) -> NDArray[np.float64]: ...
    @property
    def stderr(self) -> NDArray[np.float64]: ...
    @property
    def n(self) -> int: ...
    @property
    def strategy(self) -> str: ...

def irradiance(env: EnvMap, normal: ArrayLike, n: int, *, strategy: _Strategy = "mis",
               seed: int | np.random.Generator | None = 0,
               heuristic: Literal["balance", "power"] = "power") -> Estimate: ...
def reflected_radiance(env: EnvMap, phong: Phong, normal: ArrayLike, wi: ArrayLike, n: int, *,
                       strategy: _Strategy = "mis", seed: int | np.random.Generator | None = 0,
                       heuristic: Literal["balance", "power"] = "power") -> Estimate: ...
