"""Meshes to render: :func:`icosphere`, :func:`bumpy_sphere`."""

from __future__ import annotations

import numpy as np

__all__ = ["bumpy_sphere", "icosphere"]


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


def bumpy_sphere(rows: int = 251, cols: int = 400, bumps: float = 0.05,
                 frequency: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere with smooth bumps as a latitude-longitude triangle
    mesh: ``rows`` rings of vertices from pole to pole (the poles one vertex
    each), ``cols`` vertices a ring, the radius at polar angle θ and azimuth
    φ being ``1 + bumps · sin(frequency θ) · cos(frequency φ)``.

    Returns (vertices ((rows - 2) * cols + 2, 3) float64, faces
    (2 * cols * (rows - 2), 3) int64), counter-clockwise seen from outside:
    the defaults give 199,200 triangles, ``rows=502, cols=1000`` 10^6.
    Generated, not read: the mesh benchmarks need no data file."""
    if rows < 3 or cols < 3:
        raise ValueError(f"bumpy_sphere needs rows >= 3 and cols >= 3, got {rows}, {cols}")
    theta = np.linspace(0.0, np.pi, rows)[1:-1, None]
    phi = np.linspace(0.0, 2 * np.pi, cols, endpoint=False)[None, :]
    r = 1 + bumps * np.sin(frequency * theta) * np.cos(frequency * phi)
    ring = np.stack([r * np.sin(theta) * np.cos(phi), r * np.cos(theta),
                     -r * np.sin(theta) * np.sin(phi)], axis=-1).reshape(-1, 3)
    north, south = len(ring), len(ring) + 1
    vertices = np.concatenate([ring, [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]])
    j = np.arange(cols)
    j1 = (j + 1) % cols
    i = np.arange(rows - 3)[:, None] * cols
    a, b, c, d = i + j, i + j1, i + cols + j, i + cols + j1
    quads = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3),
                            np.stack([b, c, d], -1).reshape(-1, 3)])
    last = (rows - 3) * cols
    caps = np.concatenate([np.stack([np.full(cols, north), j, j1], -1),
                           np.stack([last + j, np.full(cols, south), last + j1], -1)])
    return vertices, np.concatenate([quads, caps]).astype(np.int64)
