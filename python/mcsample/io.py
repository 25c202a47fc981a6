"""Image files: OpenEXR (read, with layers, and write), Radiance .hdr (read),
PNG (read as linear, and write tone-mapped), ``read_image`` for any of them
(told by the file's first bytes); meshes: PLY and OBJ (read), PLY (write). Images are float32 arrays (H, W, 3) of linear RGB, row 0 at the
top; an EXR with alpha reads as (H, W, 4). Unreadable or truncated files raise
OSError naming the path; wrong arrays raise ValueError."""

from __future__ import annotations

import os

import numpy as np

from ._core.io import (encode_png, read_exr, read_hdr, read_image, read_mesh, read_png,
                       write_exr, write_png)

__all__ = ["encode_png", "read_exr", "read_hdr", "read_image", "read_mesh", "read_png", "write_exr",
           "write_ply", "write_png"]


def write_ply(path: str | os.PathLike[str], vertices: np.ndarray, faces: np.ndarray,
              normals: np.ndarray | None = None) -> None:
    """Writes a binary little-endian PLY: float vertices (and normals),
    int faces."""
    v = np.asarray(vertices, dtype="<f4")
    f = np.asarray(faces, dtype="<i4")
    props = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals is not None else [])
    cols = v if normals is None else np.hstack([v, np.asarray(normals, dtype="<f4")])
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(v)}"]
    header += [f"property float {p}" for p in props]
    header += [f"element face {len(f)}", "property list uchar int vertex_indices",
               "end_header"]
    faces_rec = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces_rec["n"], faces_rec["i"] = 3, f
    with open(path, "wb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        fh.write(np.ascontiguousarray(cols, dtype="<f4").tobytes())
        fh.write(faces_rec.tobytes())
