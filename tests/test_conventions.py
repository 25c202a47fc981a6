"""The binding conventions every kernel shares: array-likes in, precision
kept, unbatched single points, messages that name the argument and index,
thread control, and no Rust panic reaching Python."""

import os
import subprocess
import sys

import numpy as np
import pytest

import mcsample as mcs
from mcsample import warp


def test_array_likes_are_accepted():
    u = [[0.1, 0.2], [0.3, 0.4]]
    ref = warp.square_to_uniform_disk(np.array(u))
    assert np.array_equal(warp.square_to_uniform_disk(u), ref)
    assert np.array_equal(warp.square_to_uniform_disk(tuple(map(tuple, u))), ref)
    ints = warp.square_to_uniform_disk([[0, 1], [1, 0]])
    assert ints.dtype == np.float64 and ints.shape == (2, 2)


def test_float32_in_float32_out_computed_in_float32():
    u = mcs.uniform(1000, 2, seed=3)
    out32 = warp.square_to_cosine_hemisphere(u.astype(np.float32))
    out64 = warp.square_to_cosine_hemisphere(u)
    assert out32.dtype == np.float32 and out64.dtype == np.float64
    assert np.allclose(out32, out64, atol=1e-3)
    assert warp.square_to_cosine_hemisphere_pdf(out32).dtype == np.float32
    assert warp.square_to_uniform_disk(u.astype(np.float16)).dtype == np.float64


def test_non_contiguous_input():
    big = mcs.uniform(100, 4, seed=2)
    view = big[::3, 1:3]
    assert not view.flags.c_contiguous
    assert np.array_equal(warp.square_to_uniform_sphere(view),
                          warp.square_to_uniform_sphere(np.ascontiguousarray(view)))
    fortran = np.asfortranarray(big[:, :2])
    assert np.array_equal(warp.square_to_uniform_sphere(fortran),
                          warp.square_to_uniform_sphere(big[:, :2].copy()))


def _views(a: np.ndarray) -> list[np.ndarray]:
    """Non-contiguous views with the values of ``a`` (C-ordered): strided,
    reversed, a transposed view of a larger array and, for two axes or
    more, Fortran-ordered."""
    wide = np.ascontiguousarray(np.stack([a, a], axis=-1))  # (..., K, 2)
    views = [np.repeat(a, 2, axis=0)[::2], np.ascontiguousarray(a[::-1])[::-1],
             np.moveaxis(wide, -1, 0)[0], np.asfortranarray(a)]
    views = views if a.ndim > 1 else views[:3]
    assert all(not v.flags.c_contiguous and np.array_equal(v, a) for v in views)
    return views


@pytest.mark.parametrize("batch", [(), (7,), (1000,), (5, 4), (3, 2, 4), (2, 3, 2, 5),
                                   (100_003,), (301, 7, 40), (300, 600)])
def test_non_contiguous_inputs_of_every_rank_read_as_their_copies(batch, tmp_path):
    """Every binding that copies a non-contiguous input into C order (by
    its number of axes: 1 to 4 and more) reads the same values as from
    the C-ordered copy: points of any batch rank, broadcast points, a
    2D table, envmap images (lat-long and cube) and an image written to
    an EXR file. The points of the last three batches, and the table of
    the last, are large enough (65536 values and more) to be copied in
    blocks on mcsample's threads (large images: the next test)."""
    u = mcs.uniform(int(np.prod(batch)) or 1, 2, seed=9).reshape(batch + (2,) if batch else (2,))
    ref = warp.square_to_uniform_sphere(u)
    for view in _views(u):
        assert np.array_equal(warp.square_to_uniform_sphere(view), ref)
    one = np.broadcast_to(u.reshape(-1, 2)[0], batch + (2,))
    assert np.array_equal(warp.square_to_uniform_sphere(one),
                          warp.square_to_uniform_sphere(one.copy()))
    if len(batch) == 2:
        table = mcs.uniform(batch[0] * batch[1], 1, seed=4).reshape(batch) + 0.1
        ref = mcs.Discrete2D(table).sample(mcs.uniform(100, 2, seed=5))
        for view in _views(table):
            assert np.array_equal(mcs.Discrete2D(view).sample(mcs.uniform(100, 2, seed=5)), ref)
    d = warp.square_to_uniform_sphere(mcs.uniform(200, 2, seed=6))
    for mapping, shape in [("latlong", (4, 8, 3)), ("cube", (6, 4, 4, 3))]:
        # float32, which is read as it is (float64 would be cast, and the
        # cast made C-ordered, before the copy).
        image = mcs.uniform(int(np.prod(shape)), 1, seed=7).reshape(shape).astype(np.float32)
        ref = mcs.EnvMap(image, mapping=mapping)
        for view in _views(image):
            env = mcs.EnvMap(view, mapping=mapping)
            assert np.array_equal(env.eval(d), ref.eval(d))
            assert np.array_equal(env.pdf(d), ref.pdf(d))
            if mapping == "latlong":
                path = tmp_path / "view.exr"
                mcs.io.write_exr(path, view)
                assert np.array_equal(mcs.io.read_exr(path), image)


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_large_non_contiguous_images_read_the_same_on_any_thread_count(threads):
    """A lat-long image of 393216 values, in each non-contiguous layout,
    copied in blocks on ``threads`` threads: the same texels and map as
    from C order. Before each copy, a dropped batch output of the copy's
    size (other values) leaves a recycled memory map for it, so that a
    texel the copy missed cannot hold the right value by chance."""
    mcs.set_num_threads(threads)
    image = mcs.uniform(256 * 512 * 3, 1, seed=8).reshape(256, 512, 3).astype(np.float32)
    d = warp.square_to_uniform_sphere(mcs.uniform(500, 2, seed=6))
    ref = mcs.EnvMap(image)
    for k, view in enumerate(_views(image)):
        other = warp.square_to_uniform_sphere(mcs.uniform(256 * 512, 2, seed=20 + k)
                                              .astype(np.float32))
        assert other.nbytes == image.nbytes
        del other
        env = mcs.EnvMap(view)
        assert np.array_equal(env.image, image)
        assert np.array_equal(env.eval(d), ref.eval(d))
        assert np.array_equal(env.pdf(d), ref.pdf(d))


def test_single_points_come_back_unbatched():
    d = warp.square_to_uniform_sphere([0.25, 0.5])
    assert d.shape == (3,)
    assert np.ndim(warp.square_to_uniform_sphere_pdf(d)) == 0
    assert np.ndim(warp.interval_to_power(0.5, 2.0)) == 0
    assert warp.interval_to_power([0.5, 0.25], 2.0).shape == (2,)
    assert warp.square_to_uniform_sphere(np.zeros((0, 2))).shape == (0, 3)


def test_u_equal_one_is_valid_and_stays_inside():
    d = warp.square_to_uniform_sphere([[1.0, 1.0], [1.0, 0.0]])
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    p = warp.square_to_uniform_disk_concentric([[1.0, 1.0]])
    assert np.all(warp.square_to_uniform_disk_concentric_pdf(p) > 0)


@pytest.mark.parametrize("u,fragment", [
    ([[0.1, 0.2], [0.3, 1.5]], "u[1, 1] = 1.5: must lie in [0, 1]"),
    ([[0.1, float("nan")]], "u[0, 1] = NaN"),
    ([[-0.0, 0.5], [-1e-9, 0.5]], "u[1, 0] = -0.000000001"),
    ([0.5, 2.0], "u[1] = 2"),
    ([[0.1, 0.2, 0.3]], "u must have shape (N, 2), (..., 2) or (2,), got (1, 3)"),
    (np.zeros((2, 2, 3)), "got (2, 2, 3)"),
    (np.full((2, 3, 2), 0.5) + np.eye(3)[None, :, :2], "u[0, 0, 0] = 1.5"),
])
def test_bad_u_names_argument_and_index(u, fragment):
    with pytest.raises(ValueError) as excinfo:
        warp.square_to_uniform_disk(u)
    assert fragment in str(excinfo.value)


def test_leading_axes_as_numpys_ufuncs():
    """(..., k) batches: the result keeps the leading axes, equal to the
    flattened batch's result reshaped; pairs broadcast a single point
    against them and refuse other batch shapes by name."""
    u = mcs.uniform(24, 2, seed=3)
    d = warp.square_to_uniform_sphere(u.reshape(2, 3, 4, 2))
    assert d.shape == (2, 3, 4, 3)
    assert np.array_equal(d, warp.square_to_uniform_sphere(u).reshape(2, 3, 4, 3))
    pdf = warp.square_to_uniform_sphere_pdf(d)
    assert pdf.shape == (2, 3, 4)
    out = np.empty((2, 3, 4, 3))
    assert warp.square_to_uniform_sphere(u.reshape(2, 3, 4, 2), out=out) is out
    assert np.array_equal(out, d)

    phong = mcs.Phong(0.3, 0.4, 20.0)
    wi = np.array([0.0, 0.6, 0.8])
    u3 = mcs.uniform(24, 3, seed=4)
    s = phong.sample(wi, u3.reshape(4, 6, 3))
    assert s.wo.shape == (4, 6, 3) and s.pdf.shape == (4, 6)
    assert np.array_equal(s.wo, phong.sample(wi, u3).wo.reshape(4, 6, 3))
    assert phong.eval(wi, s.wo).shape == (4, 6, 3)
    with pytest.raises(ValueError, match=r"wi has batch shape \(4, 6\) and wo \(2, 6\)"):
        phong.eval(s.wo, s.wo[:2])

    env = mcs.EnvMap()
    e = env.sample(u.reshape(3, 8, 2))
    assert e.direction.shape == (3, 8, 3)
    assert np.allclose(env.pdf(e.direction), e.pdf)
    table = mcs.Discrete2D(np.arange(1.0, 7.0).reshape(2, 3))
    cells = table.sample(u.reshape(6, 4, 2))
    assert cells.shape == (6, 4, 2)
    assert np.array_equal(table.pmf(cells), table.pmf(cells.reshape(-1, 2)).reshape(6, 4))


def test_first_bad_index_found_in_a_large_parallel_batch():
    u = mcs.uniform(500_000, 2, seed=4)
    u[123_456, 0] = np.inf
    u[400_000, 1] = -1
    with pytest.raises(ValueError, match=r"u\[123456, 0\] = inf"):
        warp.square_to_uniform_disk(u)


def test_wrong_types_raise_type_error():
    with pytest.raises(TypeError, match="u must be an array of numbers"):
        warp.square_to_uniform_disk("abc")
    with pytest.raises(TypeError):
        warp.square_to_cosine_power_hemisphere([0.5, 0.5], "ten")
    with pytest.raises(TypeError, match="seed must be an integer"):
        mcs.Rng(1.5)


@pytest.mark.parametrize("call,fragment", [
    (lambda: mcs.Rng(-1), "seed = -1"),
    (lambda: mcs.Rng(2**64), "seed = 18446744073709551616"),
    (lambda: mcs.Rng(0, 2**63), "stream = 9223372036854775808"),
    (lambda: mcs.uniform(-5), "n = -5"),
    (lambda: mcs.uniform(10**30), "n = 1000000000000000000000000000000"),
    (lambda: mcs.set_num_threads(0), "n = 0"),
    (lambda: mcs.set_num_threads(2**80), "n = "),
    (lambda: mcs.Rng().advance(-1), "n = -1"),
    (lambda: mcs.Rng().random((2**30, 2**30)), "shape"),
])
def test_bad_integers_are_value_errors_not_overflow(call, fragment):
    with pytest.raises(ValueError) as excinfo:
        call()
    assert not isinstance(excinfo.value, OverflowError)
    assert fragment in str(excinfo.value)


def test_bad_dtype():
    with pytest.raises(TypeError, match="dtype must be float32 or float64"):
        mcs.Rng().random(3, dtype=np.int32)


def test_a_rust_panic_becomes_runtime_error():
    # A deliberate panic on a pool thread, through the same path as every
    # batch kernel: it must be an ordinary Exception, not PanicException.
    with pytest.raises(RuntimeError, match="internal error in mcsample"):
        mcs._core._trigger_panic()
    assert mcs.uniform(3).shape == (3, 2)  # still usable afterwards


def _run(code, **env):
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=dict(os.environ, **env), timeout=120)


def test_thread_count_from_environment():
    out = _run("import mcsample as m; print(m.get_num_threads())", MCSAMPLE_NUM_THREADS="1")
    assert out.stdout.strip() == "1", out.stderr
    out = _run("import mcsample as m\ntry:\n m.get_num_threads()\nexcept ValueError as e:\n print(e)",
               MCSAMPLE_NUM_THREADS="lots")
    assert "MCSAMPLE_NUM_THREADS" in out.stdout and "lots" in out.stdout, out.stderr


def test_pool_survives_fork():
    code = (
        "import os, mcsample as m\n"
        "a = m.uniform(200000, 2, seed=1)\n"
        "pid = os.fork()\n"
        "if pid == 0:\n"
        "    b = m.uniform(200000, 2, seed=1)\n"
        "    os._exit(0 if (a == b).all() else 3)\n"
        "_, status = os.waitpid(pid, 0)\n"
        "print(os.waitstatus_to_exitcode(status))\n"
    )
    out = _run(code)
    assert out.stdout.strip() == "0", out.stderr


@pytest.mark.skipif(not sys.platform.startswith("linux") or len(os.sched_getaffinity(0)) < 2
                    or len(os.sched_getaffinity(0)) >= 1024,
                    reason="pins on Linux with 2 to 1023 CPUs; reads /proc")
def test_pool_threads_get_a_cpu_each_when_there_is_one_per_cpu():
    # Left to the OS, the two threads of a 2-core machine often shared one
    # CPU for many short batches in a row. With one thread per CPU the
    # process may use, each is pinned to its own; with more threads than
    # CPUs, or fewer, none is (one thread runs batches on the caller).
    code = (
        "import os, mcsample as m\n"
        "cpus = sorted(os.sched_getaffinity(0))\n"
        "m.set_num_threads(len(cpus) + int(os.environ['EXTRA']))\n"
        "m.uniform(1 << 20, 2)\n"
        "print(sorted(sorted(os.sched_getaffinity(int(t))) for t in os.listdir('/proc/self/task')\n"
        "             if open(f'/proc/self/task/{t}/comm').read().startswith('mcsample-')))\n"
    )
    cpus = sorted(os.sched_getaffinity(0))
    fewer = len(cpus) - 1
    for extra, expected in [(0, [[c] for c in cpus]), (1, [cpus] * (len(cpus) + 1)),
                            (-1, [cpus] * fewer if fewer > 1 else [])]:
        out = _run(code, EXTRA=str(extra))
        assert out.stdout.strip() == str(expected), (extra, out.stderr)


def test_version():
    assert mcs.__version__.count(".") == 2


def test_out_receives_the_result_as_numpy_ufuncs_do():
    u = mcs.uniform(1000, 2, seed=5)
    out = np.empty((1000, 3))
    got = warp.square_to_uniform_sphere(u, out=out)
    assert got is out
    assert np.array_equal(out, warp.square_to_uniform_sphere(u))
    out32 = np.empty((1000, 3), np.float32)
    warp.square_to_cosine_hemisphere(u.astype(np.float32), "polar", out=out32)
    assert np.array_equal(out32, warp.square_to_cosine_hemisphere(u.astype(np.float32), "polar"))
    pdf = np.empty(1000)
    assert warp.square_to_uniform_sphere_pdf(out, out=pdf) is pdf


def test_an_unbatched_result_into_out_is_out_itself():
    """As numpy's ufuncs (``np.sqrt(2.0, out=np.empty(()))`` is the 0-d
    ``out``): one point's scalar result written into a 0-d ``out`` comes
    back as that array; without ``out`` it is a numpy scalar."""
    assert isinstance(np.sqrt(2.0, out=np.empty(())), np.ndarray)
    d = np.array([0.0, 0.0, 1.0])
    pdf = np.empty(())
    got = warp.square_to_uniform_sphere_pdf(d, out=pdf)
    assert got is pdf and pdf[()] == pytest.approx(1 / (4 * np.pi))
    assert isinstance(warp.square_to_uniform_sphere_pdf(d), np.float64)
    table = mcs.Discrete1D([1.0, 2.0, 3.0])
    index = np.full((), -7, np.int64)
    assert table.sample(0.5, out=index) is index and index[()] == table.sample(0.5)
    env = mcs.EnvMap()
    value = np.empty(())
    assert env.pdf(d, out=value) is value and value[()] == env.pdf(d)
    # The arrays of a tuple out= are the record's fields, 0-d too.
    outs = (np.empty(3), np.empty(()), np.empty(3))
    s = env.sample([0.3, 0.6], out=outs)
    assert s.direction is outs[0] and s.pdf is outs[1] and s.weight is outs[2]
    outs = (np.empty((), np.int64), np.empty(()))
    r = table.sample_reuse(0.5, out=outs)
    assert r.index is outs[0] and r.u is outs[1]


@pytest.mark.parametrize("out,exc,fragment", [
    (np.empty((1000, 3), np.float32), TypeError, "dtype float64"),
    (np.empty((999, 3)), ValueError, "out must have shape (1000, 3) (a writeable C-ordered array), got (999, 3)"),
    (np.empty((3, 1000)).T, ValueError, "C-ordered"),
    ([[0.0] * 3] * 1000, TypeError, "out must be a numpy array"),
])
def test_bad_out_is_refused(out, exc, fragment):
    u = mcs.uniform(1000, 2, seed=5)
    with pytest.raises(exc) as info:
        warp.square_to_uniform_sphere(u, out=out)
    assert fragment in str(info.value)


def test_out_must_not_be_an_input():
    u = mcs.uniform(1000, 2, seed=5)
    with pytest.raises(ValueError, match="share memory"):
        warp.square_to_uniform_disk(u, out=u)
    frozen = np.empty((1000, 2))
    frozen.flags.writeable = False
    with pytest.raises(ValueError, match="writeable"):
        warp.square_to_uniform_disk(u, out=frozen)


def test_large_batches_stream_the_same_bits():
    # Outputs of 16 MB or more are written with non-temporal stores, in
    # blocks, on all threads: the bits must equal those of small batches,
    # also into an output that is not 16-byte aligned.
    u = mcs.uniform(1_000_003, 2, seed=8)
    big = warp.square_to_uniform_sphere(u)
    small = np.concatenate([warp.square_to_uniform_sphere(u[i:i + 4099])
                            for i in range(0, len(u), 4099)])
    assert np.array_equal(big, small)
    backing = np.empty((len(u) + 1, 3))
    out = backing[1:]  # offset by 24 bytes
    assert out.ctypes.data % 16 != 0
    warp.square_to_uniform_sphere(u, out=out)
    assert np.array_equal(out, small)
    u32 = u.astype(np.float32)
    big32 = warp.square_to_uniform_disk(np.concatenate([u32] * 3))
    assert np.array_equal(big32[:len(u)], warp.square_to_uniform_disk(u32[:len(u)]))


def test_every_instruction_set_gives_the_same_bits(tmp_path):
    # Batch loops dispatch to AVX-512, AVX2 + FMA or the baseline target;
    # MCSAMPLE_SIMD caps the choice. Each path must round the same way.
    code = (
        "import sys, numpy as np, mcsample as mcs\n"
        "from mcsample import warp\n"
        "u = mcs.uniform(100_003, 3, seed=4)\n"
        "out = {}\n"
        "for dt in (np.float64, np.float32):\n"
        "    v = u.astype(dt)\n"
        "    out[f'sphere{dt.__name__}'] = warp.square_to_uniform_sphere(v[:, :2])\n"
        "    out[f'cosine{dt.__name__}'] = warp.square_to_cosine_hemisphere(v[:, :2])\n"
        "    out[f'cone{dt.__name__}'] = warp.square_to_uniform_cone(v[:, :2], 0.3)\n"
        "    out[f'power{dt.__name__}'] = warp.square_to_cosine_power_hemisphere(v[:, :2], 37.0)\n"
        "    out[f'phong{dt.__name__}'] = mcs.Phong(0.3, 0.6, 20.0).sample([0.6, 0, 0.8], v).weight\n"
        "np.savez(sys.argv[1], **out)\n"
    )
    results = {}
    for level in ("avx512", "avx2", "baseline"):
        path = tmp_path / f"{level}.npz"
        env = dict(os.environ, MCSAMPLE_SIMD=level)
        done = subprocess.run([sys.executable, "-c", code, str(path)], env=env,
                              capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr[-2000:]
        results[level] = np.load(path)
    for key in results["avx512"].files:
        for level in ("avx2", "baseline"):
            assert np.array_equal(results["avx512"][key], results[level][key]), (key, level)
