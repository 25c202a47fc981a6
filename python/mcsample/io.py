"""Image files: OpenEXR (read and write), Radiance .hdr (read), PNG (write,
tone-mapped). Images are float32 arrays (H, W, 3) of linear RGB, row 0 at the
top; an EXR with alpha reads as (H, W, 4). Unreadable or truncated files raise
OSError naming the path; wrong arrays raise ValueError."""

from __future__ import annotations

import os

import numpy as np

from ._core.io import read_exr, read_hdr, read_mesh, write_exr, write_png

__all__ = ["read_exr", "read_hdr", "read_image", "read_mesh", "write_exr", "write_png"]


def read_image(path: str | os.PathLike[str]) -> np.ndarray:
    """Reads an ``.exr`` or ``.hdr`` file, chosen by its extension.

    Returns an ndarray (H, W, 3) float32 (or (H, W, 4) for an EXR with alpha).
    """
    ext = os.path.splitext(os.fspath(path))[1].lower()
    if ext == ".exr":
        return read_exr(path)
    if ext in (".hdr", ".rgbe", ".pic"):
        return read_hdr(path)
    raise OSError(f"{os.fspath(path)}: unknown image type {ext!r} (expected .exr or .hdr)")
