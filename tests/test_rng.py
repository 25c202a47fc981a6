"""PCG32: reference outputs, agreement with Dr.Jit, jump-ahead, batches that
do not depend on the thread count."""

import numpy as np
import pytest

import mcsample as mcs

# pcg32_srandom_r(42, 54): the first outputs printed by the reference
# implementation's demo (pcg-c-basic, pcg32-demo.c).
REFERENCE_42_54 = [0xA15C02B7, 0x7B47F409, 0xBA1D3330, 0x83D2F293, 0xBFA4784B, 0xCBED606E]


def test_matches_published_pcg32_outputs():
    assert mcs.Rng(42, 54).next_uint32(6).tolist() == REFERENCE_42_54


def test_floats_are_the_uint32_outputs_scaled():
    bits = mcs.Rng(7, 3).next_uint32(1000).astype(np.float64)
    assert np.array_equal(mcs.Rng(7, 3).random(1000), bits / 2**32)
    f32 = mcs.Rng(7, 3).random(1000, dtype=np.float32)
    assert f32.dtype == np.float32
    assert np.array_equal(f32, (np.floor(bits / 2**9) / 2**23).astype(np.float32))


@pytest.mark.parametrize("seed,stream", [(0, 0), (1, 0), (42, 54), (2**64 - 1, 2**63 - 1)])
def test_matches_drjit_pcg32(seed, stream):
    dr = pytest.importorskip("drjit")
    from drjit.scalar import PCG32

    ref = PCG32(1, seed, stream)
    f64 = [ref.next_float64() for _ in range(64)]
    ref = PCG32(1, seed, stream)
    f32 = [ref.next_float32() for _ in range(64)]
    assert mcs.Rng(seed, stream).random(64).tolist() == f64
    assert mcs.Rng(seed, stream).random(64, dtype="float32").tolist() == f32
    assert dr is not None


def test_advance_is_jump_ahead():
    a, b = mcs.Rng(9), mcs.Rng(9)
    a.random(12345)
    b.advance(12345)
    assert a.random() == b.random()
    c = mcs.Rng(9)
    c.advance(2**64 - 1)  # one full period less one step: O(log n), not a loop
    assert np.isfinite(c.random())


def test_streams_differ_and_copies_are_independent():
    assert not np.array_equal(mcs.Rng(1, 0).random(8), mcs.Rng(1, 1).random(8))
    r = mcs.Rng(3)
    c = r.copy()
    assert r.random() == c.random()
    assert repr(mcs.Rng(3, 4)) == "Rng(seed=3, stream=4)"


def test_uniform_is_the_stream_of_rng():
    u = mcs.uniform(1000, 3, seed=5)
    assert u.shape == (1000, 3) and u.dtype == np.float64
    assert np.array_equal(u.reshape(-1), mcs.Rng(5).random(3000))
    assert mcs.uniform(10).shape == (10, 2)
    assert mcs.uniform(10, dtype=np.float32).dtype == np.float32


def test_bit_identical_for_one_thread_and_many():
    n = 1_000_003  # large enough to be split into many chunks
    mcs.set_num_threads(1)
    one = mcs.uniform(n, 2, seed=77)
    one_warp = mcs.warp.square_to_cosine_hemisphere(one)
    mcs.set_num_threads(2)
    assert mcs.get_num_threads() == 2
    many = mcs.uniform(n, 2, seed=77)
    assert np.array_equal(one, many)
    assert np.array_equal(one_warp, mcs.warp.square_to_cosine_hemisphere(many))
    mcs.set_num_threads(7)  # more threads than cores is allowed
    assert np.array_equal(one, mcs.uniform(n, 2, seed=77))


def test_uniform_statistics():
    u = mcs.uniform(200_000, 2, seed=1)
    assert u.min() >= 0 and u.max() < 1
    assert abs(u.mean() - 0.5) < 0.005
    assert abs(np.corrcoef(u[:, 0], u[:, 1])[0, 1]) < 0.01


def test_shapes():
    r = mcs.Rng()
    assert isinstance(r.random(), (float, np.floating))
    assert r.random((2, 3, 4)).shape == (2, 3, 4)
    assert r.random([5]).shape == (5,)
    assert r.random(0).shape == (0,)
