"""Data shipped with mcsample: a small HDR sky with a sun, the default
environment map (made by ``scripts/make_sky.py``; no download at run time)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["sky_path"]


def sky_path() -> Path:
    """Path of the packaged sky: a lat-long OpenEXR (Mitsuba's envmap
    convention, Y up), 256 x 128 half-float RGB, with a sun 35 degrees above
    the horizon; dynamic range above 10^4."""
    return Path(__file__).with_name("sky.exr")
