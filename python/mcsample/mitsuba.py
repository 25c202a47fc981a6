"""Interop with Mitsuba 3: choosing a variant that works on this machine.

Mitsuba's ``llvm_ad_rgb`` variant needs a libLLVM of version 16 or newer;
with none (or an older one) Dr.Jit aborts the whole process on its first
kernel. :func:`choose_variant` therefore finds the newest libLLVM >= 16,
proves it works in a subprocess, and falls back to ``scalar_rgb`` otherwise.
"""

from __future__ import annotations

import functools
import glob
import os
import re
import subprocess
import sys
import tempfile
import time
from types import ModuleType
from typing import TYPE_CHECKING, Any, Callable, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from .rendering import RenderResult
    from .scene import Scene

__all__ = ["EmitterSample", "available", "choose_variant", "emitter_eval", "emitter_pdf", "emitter_sample",
           "envmap_dict", "envmap_emitter", "find_libllvm", "llvm_usable", "load",
           "register_phong", "render_reference"]

#: Oldest libLLVM major version Dr.Jit's LLVM backend accepts.
MIN_LLVM = 16

_SEARCH = (
    "/usr/lib/*/libLLVM*.so*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
    "/opt/homebrew/opt/llvm/lib/libLLVM*.dylib",
    "/usr/local/opt/llvm/lib/libLLVM*.dylib",
)


def _llvm_major(path: str) -> int | None:
    """Major version from a file name such as libLLVM-19.so, libLLVM.so.19.1
    or libLLVM-16.0.6.so."""
    m = re.search(r"libLLVM[-.](?:so\.)?(\d+)", os.path.basename(path))
    return int(m.group(1)) if m else None


def find_libllvm() -> str | None:
    """Path of the newest libLLVM >= 16 on this machine (``DRJIT_LIBLLVM_PATH``
    if set), or None."""
    configured = os.environ.get("DRJIT_LIBLLVM_PATH")
    if configured:
        return configured if os.path.exists(configured) else None
    found = []
    for pattern in _SEARCH:
        for path in glob.glob(pattern):
            major = _llvm_major(path)
            if major is not None and major >= MIN_LLVM:
                found.append((major, path))
    return max(found)[1] if found else None


_PROBE = """
import drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
x = dr.arange(mi.Float, 16)
print("ok", float((x * 2).numpy().sum()))
"""


@functools.lru_cache(maxsize=None)
def llvm_usable() -> bool:
    """Whether Mitsuba's llvm_ad_rgb variant runs here, checked once in a
    subprocess (so that a failure cannot abort this process)."""
    lib = find_libllvm()
    if lib is None or not available():
        return False
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=lib)
    try:
        out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True,
                             text=True, timeout=300)
    except (OSError, subprocess.TimeoutExpired):
        return False
    if out.returncode == 0 and "ok 240.0" in out.stdout:
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", lib)
        return True
    return False


@functools.lru_cache(maxsize=None)
def available() -> bool:
    """Whether the ``mitsuba`` and ``drjit`` packages can be imported."""
    try:
        import drjit  # noqa: F401
        import mitsuba  # noqa: F401
    except ImportError:
        return False
    return True


def choose_variant(prefer_llvm: bool = True) -> str:
    """``"llvm_ad_rgb"`` when it works here (and ``prefer_llvm``), else
    ``"scalar_rgb"``, which works anywhere."""
    return "llvm_ad_rgb" if prefer_llvm and llvm_usable() else "scalar_rgb"


def load(variant: str | None = None) -> ModuleType:
    """Imports Mitsuba 3 with ``variant`` set (default: :func:`choose_variant`).

    Raises ImportError when Mitsuba is not installed (``pip install
    "mcsample[mitsuba]"``), and RuntimeError for an llvm variant that cannot
    run here (instead of letting it abort the process).
    """
    if not available():
        raise ImportError('Mitsuba 3 is not installed: pip install "mcsample[mitsuba]"')
    variant = variant or choose_variant()
    if variant.startswith("llvm") and not llvm_usable():
        raise RuntimeError(f"variant {variant!r} needs a libLLVM >= {MIN_LLVM}, and none works "
                           "here (Debian: apt-get install libllvm19)")
    import mitsuba as mi

    mi.set_variant(variant)
    return mi


_REGISTERED: set[str] = set()


def register_phong() -> str:
    """Registers mcsample's Phong BSDF for the current Mitsuba variant (set
    one first, e.g. with :func:`load`) and returns its type name,
    ``"mcsample_phong"``. Its keys are ``diffuse_reflectance`` and
    ``specular_reflectance`` (a float, an RGB triple or a constant
    texture) and ``exponent``; it is written in Dr.Jit, independently of
    the Rust :class:`mcsample.Phong`, with the same formula and sampling."""
    import mitsuba as mi

    from .mitsuba_phong import TYPE_NAME, make_class

    variant = mi.variant()
    if variant is None:
        raise RuntimeError("set a Mitsuba variant first (mcsample.mitsuba.load())")
    if variant not in _REGISTERED:
        cls = make_class(mi)
        mi.register_bsdf(TYPE_NAME, lambda props: cls(props))
        _REGISTERED.add(variant)
    return TYPE_NAME


def render_reference(scene: "Scene", spp: int, seed: int = 0, integrator: str | None = None,
                     max_depth: int | None = None, rr_depth: int | None = None,
                     variant: str | None = None,
                     hide_emitters: bool | None = None) -> "RenderResult":
    """Renders ``scene`` in Mitsuba 3 (``variant``: default
    :func:`choose_variant`) with its ``path`` or ``direct`` integrator
    wrapped in ``moment``, so each pixel comes with the variance of its mean
    luminance. The film uses a box filter, as mcsample's. ``integrator``,
    ``max_depth``, ``rr_depth`` and ``hide_emitters`` default to the scene
    dict's integrator, as in :func:`mcsample.render`.

    Returns a :class:`mcsample.RenderResult` whose ``variance`` is None
    (Mitsuba reports moments in XYZ, from which per-RGB-channel variances
    cannot be recovered) and whose ``luminance_variance`` is
    (E[Y²] − E[Y]²) / (spp − 1); ``seconds`` includes Mitsuba's JIT
    compilation unless its kernels are cached from an earlier call.
    """
    from .rendering import RenderResult

    mi = load(variant)
    defaults = scene.integrator
    kind = integrator or defaults.get("integrator", "path")
    if kind not in ("path", "direct"):
        raise ValueError(f"integrator = {kind!r}: must be 'path' or 'direct'")
    nested: dict = {"type": kind,
                    "hide_emitters": bool(hide_emitters if hide_emitters is not None
                                          else defaults.get("hide_emitters", False))}
    if kind == "path":
        nested["max_depth"] = int(max_depth if max_depth is not None
                                  else defaults.get("max_depth", -1))
        nested["rr_depth"] = int(rr_depth if rr_depth is not None
                                 else defaults.get("rr_depth", 5))
    with tempfile.TemporaryDirectory(prefix="mcsample-scene-") as directory:
        d = scene.to_mitsuba(spp=spp, directory=directory)
        d["integrator"] = {"type": "moment", "nested": nested}
        mi_scene = mi.load_dict(d)

    start = time.perf_counter()
    out = np.asarray(mi.render(mi_scene, spp=spp, seed=seed), dtype=np.float64)
    seconds = time.perf_counter() - start
    # Channels: R, G, B, nested.X, Y, Z, m2_nested.X, Y, Z.
    m1, m2 = out[..., 4], out[..., 7]
    var = np.maximum(m2 - m1 * m1, 0.0) / max(spp - 1, 1)
    return RenderResult(out[..., :3].astype(np.float32), None, var.astype(np.float32),
                        spp, seconds)


# --------------------------------------------------------------------------
# Environment maps


def envmap_dict(env: Any, latlong_width: int | None = None) -> dict[str, Any]:
    """Mitsuba's ``envmap`` emitter for ``env`` as a dict for ``mi.load_dict``
    (a variant must be set): the same image, scale, rotation and MIS
    compensation. Angular and cube maps are converted to lat-long first
    (``latlong_width`` columns, default 4x the source's resolution), since
    Mitsuba's emitter takes only that form."""
    import mitsuba as mi

    if env.mapping != "latlong":
        env = env.convert("latlong", latlong_width or 4 * np.shape(env.image)[1])
    m = np.eye(4)
    m[:3, :3] = np.asarray(env.to_world)
    return {"type": "envmap", "scale": float(env.scale),
            "bitmap": mi.Bitmap(np.ascontiguousarray(env.image, dtype=np.float32)),
            "to_world": mi.ScalarTransform4f(m.tolist()),
            "mis_compensation": bool(env.compensate)}


def envmap_emitter(env: Any, latlong_width: int | None = None) -> Any:
    """Mitsuba's ``envmap`` emitter object for ``env`` (see :func:`envmap_dict`)."""
    import mitsuba as mi

    return mi.load_dict(envmap_dict(env, latlong_width))


def _per_batch(fn: Callable[..., Any], *arrays: np.ndarray) -> list[np.ndarray]:
    """Runs ``fn`` on the transposed batches (Mitsuba's vectorised types,
    one call) or, in a scalar variant, once per row; returns the outputs
    as arrays with the batch on axis 0."""
    import mitsuba as mi

    if not str(mi.variant()).startswith("scalar"):
        outputs = fn(len(arrays[0]), *(a.T for a in arrays))
        return [np.asarray(o, dtype=np.float64).T for o in outputs]
    rows = [fn(1, *row) for row in zip(*arrays)]
    return [np.array([np.asarray(r[k], dtype=np.float64) for r in rows])
            for k in range(len(rows[0]))]


def emitter_eval(emitter: Any, d: Any) -> np.ndarray:
    """Radiance (N, 3) Mitsuba's ``emitter`` sends along world directions
    ``d`` (N, 3) toward the scene (``emitter.eval`` with si.wi = -d)."""
    import drjit as dr
    import mitsuba as mi

    def fn(n: int, d: Any) -> tuple[Any]:
        si = dr.zeros(mi.SurfaceInteraction3f, n) if n > 1 else mi.SurfaceInteraction3f()
        si.wi = -mi.Vector3f(d)
        return (emitter.eval(si),)

    return _per_batch(fn, np.atleast_2d(np.asarray(d, dtype=np.float64)))[0]


def emitter_pdf(emitter: Any, d: Any) -> np.ndarray:
    """Mitsuba's ``pdf_direction`` (N,) per steradian of world directions
    ``d`` (N, 3)."""
    import drjit as dr
    import mitsuba as mi

    def fn(n: int, d: Any) -> tuple[Any]:
        it = dr.zeros(mi.Interaction3f, n) if n > 1 else mi.Interaction3f()
        ds = dr.zeros(mi.DirectionSample3f, n) if n > 1 else mi.DirectionSample3f()
        ds.d = mi.Vector3f(d)
        return (emitter.pdf_direction(it, ds),)

    return _per_batch(fn, np.atleast_2d(np.asarray(d, dtype=np.float64)))[0].reshape(-1)


class EmitterSample(NamedTuple):
    """What Mitsuba's ``sample_direction`` returns, as arrays."""

    #: World directions (N, 3).
    direction: np.ndarray
    #: Density per steradian (N,).
    pdf: np.ndarray
    #: Radiance / pdf (N, 3).
    weight: np.ndarray
    #: Mitsuba's lat-long coordinates of the sample (N, 2).
    uv: np.ndarray


def emitter_sample(emitter: Any, u: Any) -> EmitterSample:
    """Mitsuba's ``sample_direction`` for ``u`` (N, 2) in float32."""
    import drjit as dr
    import mitsuba as mi

    def fn(n: int, u: Any) -> tuple[Any, Any, Any, Any]:
        it = dr.zeros(mi.Interaction3f, n) if n > 1 else mi.Interaction3f()
        ds, weight = emitter.sample_direction(it, mi.Point2f(u))
        return ds.d, ds.pdf, weight, ds.uv

    d, pdf, weight, uv = _per_batch(fn, np.atleast_2d(np.asarray(u, dtype=np.float32)))
    return EmitterSample(d, pdf.reshape(-1), weight, uv)
