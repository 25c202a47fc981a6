"""Stub of ``mcsample._core.render``: see ``mcsample.scene`` and
``mcsample.rendering`` for the docs."""

from typing import Callable, Final, Literal, Sequence, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import EnvMap, Phong

_Matrix = Sequence[Sequence[float]]
_RGB = Sequence[float]

@final
class SceneBuilder:
    def __init__(self) -> None: ...
    def add_mesh(self, vertices: NDArray[np.float64], faces: NDArray[np.int64],
                 normals: NDArray[np.float64] | None, face_normals: bool, bsdf: Phong,
                 two_sided: bool, emission: _RGB | None) -> None: ...
    def add_sphere(self, center: _RGB, radius: float, flip_normals: bool, bsdf: Phong,
                   two_sided: bool, emission: _RGB | None) -> None: ...
    def add_disk(self, to_world: _Matrix, bsdf: Phong, two_sided: bool,
                 emission: _RGB | None) -> None: ...
    def set_envmap(self, env: EnvMap) -> None: ...
    def set_constant(self, radiance: _RGB) -> None: ...
    def set_camera(self, to_world: _Matrix, fov: float, fov_axis: Literal["x", "y", "diagonal", "smaller", "larger"], width: int, height: int,
                   near_clip: float, far_clip: float, aperture_radius: float,
                   focus_distance: float) -> None: ...
    def set_motion(self, start: _Matrix, end: _Matrix) -> None: ...
    def set_camera_motion(self, end: _Matrix) -> None: ...
    def set_filter(self, kind: Literal["box", "gaussian"], stddev: float,
                   sample_border: bool) -> None: ...
    def build(self) -> CompiledScene: ...

@final
class CompiledScene:
    film: Final[tuple[int, int]]
    ray_tracer: Final[str]
    def sample_sensor(self, x: ArrayLike, u: ArrayLike) -> NDArray[np.float64]: ...
    def sample_emitter(self, x: ArrayLike, u: ArrayLike) -> NDArray[np.float64]: ...
    def emitter_pdf(self, x: ArrayLike, d: ArrayLike) -> NDArray[np.float64] | float: ...

def render(
    scene: CompiledScene, spp: int, seed: int | np.random.Generator | None,
    integrator: Literal["direct", "path", "ptracer", "bdpt"], strategy: Literal["bsdf", "emitter", "mis"],
    heuristic: Literal["balance", "power"],
    max_depth: int, rr_depth: int, hide_emitters: bool = False,
    callback: Callable[[int], object] | None = None,
    sampler: Literal["independent", "stratified", "multijitter", "sobol", "ldsampler", "zsobol"] = "independent",
    first_sample: int | None = None, total_spp: int | None = None, keep_sums: bool = False,
    strategies: bool = False,
) -> _Film: ...

def bdpt_strategies(max_depth: int) -> list[tuple[int, int]]: ...

#: image, variance, luminance variance (flat float32), blocks as (start,
#: length), sums (flat float64, 8 per pixel and block; None unless kept).
_Film = tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32],
             list[tuple[int, int]], NDArray[np.float64] | None]

def merge(chunks: list[tuple[list[tuple[int, int]], NDArray[np.float64]]],
          pixels: int, paths_per_sample: int | None = None) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32],
                                list[tuple[int, int]], NDArray[np.float64]]: ...
