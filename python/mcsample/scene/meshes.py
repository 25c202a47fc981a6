"""Meshes to render: :func:`icosphere`."""

from __future__ import annotations

import numpy as np

__all__ = ["icosphere"]


def icosphere(subdivisions: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere as a triangle mesh: the icosahedron with each face
    split in four ``subdivisions`` times, vertices pushed onto the sphere.

    Returns (vertices (N, 3) float64, faces (20 * 4**subdivisions, 3)
    int64), counter-clockwise seen from outside; for the ``"mesh"`` shape
    of :meth:`mcsample.Scene.from_mitsuba` or :func:`mcsample.io.write_ply`."""
    t = (1 + 5 ** 0.5) / 2
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    verts = [np.array(p, dtype=np.float64) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        cache: dict[tuple[int, int], int] = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]

        f = [g for a, b, c in f for g in
             ([a, mid(a, b), mid(c, a)], [b, mid(b, c), mid(a, b)],
              [c, mid(c, a), mid(b, c)], [mid(a, b), mid(b, c), mid(c, a)])]
    return np.array(verts), np.array(f, dtype=np.int64)
