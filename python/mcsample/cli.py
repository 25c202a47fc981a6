"""The ``render`` and ``compare`` commands of ``python -m mcsample``."""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np

from . import io, stats

__all__ = ["compare_images", "load_json_scene", "render_json"]


def _resolve_paths(value: Any, base: str) -> Any:
    """``filename`` entries made relative to ``base``."""
    if isinstance(value, dict):
        return {k: (os.path.join(base, v) if k == "filename" and isinstance(v, str)
                    and not os.path.isabs(v) else _resolve_paths(v, base))
                for k, v in value.items()}
    return value


def load_json_scene(path: str) -> dict:
    """A Mitsuba scene dict from a JSON file; relative ``filename`` paths are
    taken relative to the file's folder."""
    with open(path) as f:
        d = json.load(f)
    return _resolve_paths(d, os.path.dirname(os.path.abspath(path)))


def render_json(path: str, out: str, **kwargs: Any) -> list[str]:
    """Renders the JSON scene ``path`` into ``out`` (EXR) and a PNG beside it."""
    from . import Scene, render

    scene = Scene.from_mitsuba(load_json_scene(path))
    result = render(scene, **kwargs)
    png = os.path.splitext(out)[0] + ".png"
    io.write_exr(out, result.image)
    io.write_png(png, result.image)
    print(f"{result.spp} spp in {result.seconds:.2f} s")
    return [out, png]


def compare_images(image: str, reference: str, out: str | None = None) -> str:
    """MSE, relMSE and the mean relative error of ``image`` against
    ``reference``; writes the relative error (luminance) as a PNG heat map."""
    a, b = io.read_image(image)[..., :3], io.read_image(reference)[..., :3]
    if a.shape != b.shape:
        raise ValueError(f"images differ in size: {a.shape} and {b.shape}")
    ya, yb = stats.luminance(a), stats.luminance(b)
    rel = np.abs(ya - yb) / (yb + 1e-2)
    out = out or os.path.splitext(image)[0] + "_error.png"
    heat = np.stack([np.clip(rel, 0, 1), np.clip(rel - 1, 0, 1) * 0.5, 1 - np.clip(rel, 0, 1)],
                    axis=-1).astype(np.float32)
    io.write_png(out, heat, srgb=False)
    return (f"MSE {stats.mse(a, b):.6g}  relMSE {stats.relmse(a, b):.6g}  "
            f"mean relative error {rel.mean():.4g}  (error image: {out})")
