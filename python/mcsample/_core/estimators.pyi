"""Estimators of irradiance and reflected radiance under an environment map."""

from typing import Any, final

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

def irradiance(env: EnvMap, normal: ArrayLike, n: int, strategy: str = "mis",
               seed: int | None = None, heuristic: str = "balance") -> Estimate: ...
def reflected_radiance(env: EnvMap, phong: Phong, normal: ArrayLike, wi: ArrayLike, n: int,
                       strategy: str = "mis", seed: int | None = None,
                       heuristic: str = "balance") -> Estimate: ...
