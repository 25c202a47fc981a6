"""Estimators of irradiance and reflected radiance under an environment map."""

from typing import Any, final

import numpy as np
from numpy.typing import ArrayLike

from . import EnvMap, Phong

@final
class Estimate:
    """A Monte Carlo estimate of an RGB quantity."""

    @property
    def value(self) -> Any: ...
    @property
    def stderr(self) -> Any: ...
    @property
    def n(self) -> int: ...
    @property
    def strategy(self) -> str: ...

def irradiance(env: EnvMap, normal: ArrayLike, n: int, *, strategy: str = "mis",
               seed: int | np.random.Generator | None = 0,
               heuristic: str = "power") -> Estimate: ...
def reflected_radiance(env: EnvMap, phong: Phong, normal: ArrayLike, wi: ArrayLike, n: int, *,
                       strategy: str = "mis", seed: int | np.random.Generator | None = 0,
                       heuristic: str = "power") -> Estimate: ...
