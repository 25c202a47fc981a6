"""Every public object pickles and deep-copies, and the copy gives the same
bits as the original: a ``Rng`` continues its stream exactly, a table or map
rebuilt from what it was built from samples identically (DESIGN.md,
"Pickling"). That is what multiprocessing, joblib and Dask need."""

from __future__ import annotations

import copy
import multiprocessing
import pickle
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import mcsample as mcs
from mcsample import qmc

U2 = mcs.uniform(257, 2, seed=11)
U3 = mcs.uniform(257, 3, seed=12)
DIRS = mcs.warp.square_to_uniform_sphere(U2)


def _copies(obj: Any) -> list[Any]:
    """A pickled (every protocol) and a deep-copied copy of ``obj``."""
    out = [pickle.loads(pickle.dumps(obj, protocol=p))
           for p in range(2, pickle.HIGHEST_PROTOCOL + 1)]
    return out + [copy.deepcopy(obj)]


def _same(a: Any, b: Any) -> None:
    """The same values to the bit (arrays, records, tuples, numbers)."""
    if hasattr(a, "_fields") or isinstance(a, (tuple, list)) or type(a).__name__.endswith("Sample"):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            _same(x, y)
    else:
        x, y = np.asarray(a), np.asarray(b)
        assert x.dtype == y.dtype and x.shape == y.shape
        assert x.tobytes() == y.tobytes()


def _sky(h: int = 9, w: int = 16) -> np.ndarray:
    rng = np.random.default_rng(3)
    img = rng.random((h, w, 3)).astype(np.float32) ** 4
    img[h // 3, w // 3] = 40.0
    return img


ROTATION = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], dtype=np.float64)

#: (name, object, what to compare): each ``use(obj)`` is run on the
#: original and on every copy.
CASES: list[tuple[str, Callable[[], Any], Callable[[Any], Any]]] = [
    ("Phong", lambda: mcs.Phong([0.3, 0.2, 0.1], 0.5, 40.0, selection="luminance"),
     lambda p: (p.sample([0.3, 0.1, 0.9], U3), p.eval([0, 0, 1], DIRS), p.diffuse_probability)),
    ("EnvMap latlong", lambda: mcs.EnvMap(_sky(), scale=2.5, to_world=ROTATION, compensate=True),
     lambda e: (e.sample(U2), e.pdf(DIRS), e.eval(DIRS), e.image)),
    ("EnvMap mitsuba", lambda: mcs.EnvMap(_sky(), sampling="mitsuba"),
     lambda e: (e.sample(U2), e.pdf(DIRS))),
    ("EnvMap tiny (padded)", lambda: mcs.EnvMap(_sky(1, 1)),
     lambda e: (e.sample(U2), e.pdf(DIRS), e.image)),
    ("EnvMap cube", lambda: mcs.EnvMap(_sky(6 * 4, 4).reshape(6, 4, 4, 3), mapping="cube"),
     lambda e: (e.sample(U2), e.pdf(DIRS))),
    ("EnvMap angular", lambda: mcs.EnvMap(_sky(8, 8), mapping="angular"),
     lambda e: (e.sample(U2), e.pdf(DIRS))),
    ("Frame", lambda: mcs.Frame([0.3, -0.2, 0.9]), lambda f: (f.to_local(DIRS), f.to_world(DIRS))),
    ("Frame batch", lambda: mcs.Frame(DIRS[:8].reshape(2, 4, 3) * 3.0),
     lambda f: (f.to_local(DIRS[:8].reshape(2, 4, 3)), len(f))),
    ("Discrete1D", lambda: mcs.Discrete1D(_sky()[..., 0].ravel()),
     lambda d: (d.sample(U2[:, 0]), d.sample_reuse(U2[:, 1]), d.pmf(), d.sum)),
    ("AliasTable", lambda: mcs.AliasTable(_sky()[..., 1].ravel()),
     lambda d: (d.sample(U2[:, 0]), d.pmf())),
    ("Discrete2D", lambda: mcs.Discrete2D(_sky()[..., 2]),
     lambda d: (d.sample(U2), d.sample_reuse(U2), d.pmf())),
    ("PiecewiseConstant1D", lambda: mcs.PiecewiseConstant1D(_sky()[0, :, 0], a=-1.0, b=3.0),
     lambda d: (d.sample(U2[:, 0]), d.pdf(U2[:, 1] * 4 - 1), d.domain)),
    ("PiecewiseConstant2D",
     lambda: mcs.PiecewiseConstant2D(_sky()[..., 0], domain=((0.0, 2.0), (-1.0, 1.0))),
     lambda d: (d.sample(U2), d.pdf(U2), d.domain)),
    ("PhongSample", lambda: mcs.Phong(0.3, 0.5, 20.0).sample([0, 0, 1], U3),
     lambda s: tuple(s)),
    ("EnvSample", lambda: mcs.EnvMap(_sky()).sample(U2), lambda s: tuple(s)),
    ("PiecewiseSample", lambda: mcs.PiecewiseConstant1D([1.0, 2.0]).sample(U2[:, 0]),
     lambda s: tuple(s)),
    ("Estimate", lambda: mcs.estimators.irradiance(mcs.EnvMap(_sky()), [0, 0, 1], 4096),
     lambda e: (e.value, e.stderr, e.n, e.strategy)),
]


@pytest.mark.parametrize("name, make, use", CASES, ids=[c[0] for c in CASES])
def test_copies_give_the_same_bits(name: str, make: Callable[[], Any],
                                   use: Callable[[Any], Any]) -> None:
    original = make()
    for twin in _copies(original):
        assert type(twin) is type(original)
        assert repr(twin) == repr(original)
        _same(use(twin), use(original))


def test_an_rng_continues_its_stream_exactly() -> None:
    rng = mcs.Rng(7, 3)
    rng.random(5)
    rng.next_uint32((2, 3))
    rng.advance(2**63 + 12345)  # wraps the position modulo 2**64
    rng.random(4, dtype=np.float32)
    for twin in _copies(rng):
        assert (twin.seed, twin.stream) == (7, 3)
        same_place = rng.copy()
        _same(twin.random(100), same_place.random(100))
        _same(twin.next_uint32(9), same_place.next_uint32(9))


@pytest.mark.parametrize("engine", [
    lambda: qmc.Sobol(5, seed=3), lambda: qmc.Sobol(3, scramble="lms", seed=4),
    lambda: qmc.Sobol(2, scramble=False), lambda: qmc.Halton(4, seed=5),
    lambda: qmc.LatinHypercube(3, seed=6), lambda: qmc.Stratified(4, seed=7),
    lambda: qmc.MultiJitter(2, seed=8),
], ids=["sobol", "sobol-lms", "sobol-plain", "halton", "lhs", "stratified", "multijitter"])
def test_a_qmc_engine_continues_where_it_was(engine: Callable[[], qmc._Engine]) -> None:
    e = engine()
    e.random(16)
    for twin in _copies(e):
        assert twin.num_generated == 16
        _same(twin.random(32), copy.deepcopy(e).random(32))


def _scene() -> mcs.Scene:
    return mcs.Scene.from_mitsuba({
        "type": "scene",
        "ball": {"type": "sphere", "bsdf": {"type": "diffuse"}},
        "light": {"type": "sphere", "center": [2, 2, 2], "radius": 0.3,
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [5, 5, 5]}}},
        "env": mcs.EnvMap(_sky()),
        "sensor": {"type": "perspective", "fov": 40,
                   "to_world": {"look_at": {"origin": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0]}},
                   "film": {"type": "hdrfilm", "width": 12, "height": 8}},
    })


def test_a_scene_renders_the_same_image_after_a_round_trip() -> None:
    scene = _scene()
    image = mcs.render(scene, 8, progress=False)  # compiles the original
    for twin in _copies(scene):
        again = mcs.render(twin, 8, progress=False)
        _same(again.image, image.image)
        _same(again.variance, image.variance)


def test_results_pickle() -> None:
    result = mcs.render(_scene(), 4, progress=False)
    chi2 = mcs.stats.chi2_test(mcs.warp.square_to_uniform_disk,
                               mcs.warp.square_to_uniform_disk_pdf, "disk", n=20000, res=11)
    ztest = mcs.stats.render_ztest(result, mcs.render(_scene(), 4, seed=1, progress=False))
    for obj in (result, chi2, ztest):
        for twin in _copies(obj):
            assert type(twin) is type(obj) and repr(twin) == repr(obj)
    for twin in _copies(result):
        _same(twin.image, result.image)


def _sample_in_worker(env: mcs.EnvMap) -> Any:
    return tuple(env.sample(U2))


@pytest.mark.parametrize("start", ["spawn", "fork"])
def test_objects_travel_to_worker_processes(start: str) -> None:
    """What multiprocessing does: pickle to another process and back. A
    forked child (the default start on Linux before Python 3.14) has none
    of the parent's threads: every parallel loop must run on mcsample's
    own pool, which is built again there (rayon's global pool would hang)."""
    env = mcs.EnvMap(_sky(), sampling="mitsuba")
    mcs.PiecewiseConstant2D(_sky()[..., 0])  # a build on many threads first
    pool = multiprocessing.get_context(start).Pool(1)
    try:
        remote = pool.apply_async(_sample_in_worker, (env,)).get(timeout=120)
    finally:
        pool.terminate()
    _same(remote, tuple(env.sample(U2)))
