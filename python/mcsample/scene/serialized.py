"""Mitsuba's ``.serialized`` meshes: :func:`read_serialized`.

A file holds one or more meshes, each a little-endian header (``u16``
0x041C, ``u16`` version 3 or 4) and a zlib stream: ``u32`` flags (0x0001
vertex normals, 0x0002 texture coordinates, 0x0008 vertex colours, 0x0010
face normals (ignored, as by Mitsuba 3), 0x2000 double precision), in version 4 the mesh's name (UTF-8,
NUL-terminated), ``u64`` vertex and triangle counts, then positions,
normals, texture coordinates and colours (float32, or float64), and the
triangles' vertex indices (``u32``, ``u64`` above 2**32 vertices). Several
meshes end with a table of where each starts (``u64`` offsets in version 4,
``u32`` in version 3) and their count (``u32``).
"""

from __future__ import annotations

import os
import struct
import zlib

import numpy as np

__all__ = ["read_serialized"]

MAGIC = 0x041C
VERTEX_NORMALS, TEXCOORDS, COLORS, DOUBLE = 0x1, 0x2, 0x8, 0x2000


class _Reader:
    """Reads little-endian values off a byte string, naming the file when it
    ends early."""

    def __init__(self, data: bytes, path: str) -> None:
        self.data, self.at, self.path = data, 0, path

    def take(self, n: int) -> bytes:
        if self.at + n > len(self.data):
            raise ValueError(f"{self.path}: a serialized mesh ends early (needs {n} more "
                             f"bytes at {self.at}, has {len(self.data) - self.at})")
        chunk = self.data[self.at:self.at + n]
        self.at += n
        return chunk

    def array(self, dtype: str, count: int, width: int) -> np.ndarray:
        size = np.dtype(dtype).itemsize * count * width
        return np.frombuffer(self.take(size), dtype=dtype).reshape(count, width)


def _offset(data: bytes, path: str, shape_index: int, version: int) -> int:
    """Where mesh ``shape_index`` starts: 0, or by the table at the end."""
    if shape_index == 0:
        return 0
    count = struct.unpack_from("<I", data, len(data) - 4)[0] if len(data) >= 8 else 0
    width = 8 if version >= 4 else 4
    table = len(data) - 4 - count * width
    if table < 0:
        count = 1  # no table of offsets: a file of one mesh
    if shape_index >= count:
        raise ValueError(f"{path}: shape_index = {shape_index}, but the file holds "
                         f"{count} mesh{'es' if count > 1 else ''}")
    return struct.unpack_from("<Q" if width == 8 else "<I", data, table + shape_index * width)[0]


def read_serialized(path: str | os.PathLike[str], shape_index: int = 0
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Mesh ``shape_index`` of a Mitsuba ``.serialized`` file.

    Returns
    -------
    (vertices (N, 3) float64, faces (M, 3) int64, normals (N, 3) float64 or
    None). The file's face-normals flag is ignored, as Mitsuba 3 does (the
    shape's ``face_normals`` key decides).

    Raises OSError when the file cannot be read and ValueError naming the
    file when it is not a serialized mesh (or ends early, or has no mesh
    ``shape_index``).
    """
    path = os.fspath(path)
    with open(path, "rb") as f:
        data = f.read()
    if isinstance(shape_index, bool) or not isinstance(shape_index, (int, np.integer)) \
            or shape_index < 0:
        raise ValueError(f"shape_index = {shape_index!r}: must be an integer >= 0")
    if len(data) < 4:
        raise ValueError(f"{path}: not a Mitsuba serialized mesh (too short)")
    version = struct.unpack_from("<H", data, 2)[0]
    start = _offset(data, path, int(shape_index), version)
    magic, version = struct.unpack_from("<HH", data, start) if start + 4 <= len(data) else (0, 0)
    if magic != MAGIC or version not in (3, 4):
        raise ValueError(f"{path}: not a Mitsuba serialized mesh (header {magic:#06x}, "
                         f"version {version} at byte {start})")
    try:
        stream = zlib.decompressobj().decompress(data[start + 4:])
    except zlib.error as e:
        raise ValueError(f"{path}: the mesh's zlib stream is damaged: {e}") from None
    r = _Reader(stream, path)
    flags = struct.unpack("<I", r.take(4))[0]
    if version >= 4:
        end = stream.find(b"\0", r.at)
        if end < 0:
            raise ValueError(f"{path}: a serialized mesh ends early (in its name)")
        r.at = end + 1
    n_vertices, n_faces = struct.unpack("<QQ", r.take(16))
    real = "<f8" if flags & DOUBLE else "<f4"
    vertices = r.array(real, n_vertices, 3).astype(np.float64)
    normals = r.array(real, n_vertices, 3).astype(np.float64) if flags & VERTEX_NORMALS else None
    if flags & TEXCOORDS:
        r.array(real, n_vertices, 2)
    if flags & COLORS:
        r.array(real, n_vertices, 3)
    index = "<u8" if n_vertices > 0xFFFFFFFF else "<u4"
    faces = r.array(index, n_faces, 3).astype(np.int64)
    if faces.size and faces.max() >= n_vertices:
        raise ValueError(f"{path}: mesh {shape_index} has a vertex index {int(faces.max())} "
                         f"past its {n_vertices} vertices")
    return vertices, faces, normals
