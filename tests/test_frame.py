"""mcs.Frame: orthonormal, right-handed, stable near both poles, batched."""

import numpy as np

import mcsample as mcs
from mcsample import warp


def _normals():
    d = warp.square_to_uniform_sphere(mcs.uniform(5000, 2, seed=2))
    eps = np.array([1e-4, 1e-8, 1e-12, 0.0])
    near = [[e, -e, s * np.sqrt(1 - 2 * e * e)] for e in eps for s in (1, -1)]
    return np.concatenate([d, near, [[-0.0, -0.0, -1.0], [1, 0, 0], [0, 1, 0]]])


def test_orthonormal_right_handed_everywhere():
    n = _normals()
    f = mcs.Frame(n)
    s, t, nn = f.s, f.t, f.n
    for a, b in [(s, t), (s, nn), (t, nn)]:
        assert np.abs(np.sum(a * b, axis=1)).max() < 1e-12
    for a in (s, t, nn):
        assert np.abs(np.linalg.norm(a, axis=1) - 1).max() < 1e-12
    assert np.abs(np.cross(s, t) - nn).max() < 1e-12


def test_local_world_round_trip_and_normal_is_z():
    n = _normals()
    f = mcs.Frame(n)
    v = warp.square_to_uniform_sphere(mcs.uniform(len(n), 2, seed=3))
    local = f.to_local(v)
    assert np.abs(f.to_world(local) - v).max() < 1e-12
    assert np.allclose(f.to_local(n), [0, 0, 1], atol=1e-12)
    # One vector for all rows broadcasts.
    assert np.allclose(f.to_world([0, 0, 1]), n, atol=1e-12)


def test_single_normal_batches_vectors_and_keeps_float32():
    f = mcs.Frame([0, 0, 2.0])  # normalised
    assert np.allclose(f.n, [0, 0, 1])
    v = mcs.uniform(100, 3, seed=1).astype(np.float32)
    out = f.to_local(v)
    assert out.dtype == np.float32 and out.shape == (100, 3)
    assert np.allclose(f.to_world(out), v, atol=1e-6)
    # Lobe samples around a tilted normal have their cosine along it.
    g = mcs.Frame([1.0, 1.0, 0.0])
    d = g.to_world(warp.square_to_cosine_hemisphere(mcs.uniform(1000, 2, seed=4)))
    assert np.all(d @ (np.array([1, 1, 0]) / np.sqrt(2)) >= -1e-12)
