"""Choosing a Mitsuba 3 variant that works on this machine.

Mitsuba's ``llvm_ad_rgb`` variant needs a libLLVM of version 16 or newer;
with none (or an older one) Dr.Jit aborts the whole process on its first
kernel. :func:`choose_variant` therefore finds the newest libLLVM >= 16,
proves it works in a subprocess, and falls back to ``scalar_rgb`` otherwise.
"""

from __future__ import annotations

import contextlib
import functools
import glob
import os
import re
import subprocess
import sys
from types import ModuleType
from typing import Iterator

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


@contextlib.contextmanager
def variant_set(variant: str | None = None) -> Iterator[ModuleType]:
    """Mitsuba with ``variant`` set (as :func:`load`) for the body of a
    ``with`` block, then the caller's variant again (none stays none)."""
    import mitsuba as mi

    before = mi.variant()
    try:
        yield load(variant)
    finally:
        if before is not None and mi.variant() != before:
            mi.set_variant(before)
