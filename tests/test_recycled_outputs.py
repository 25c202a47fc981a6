"""Large fresh outputs (1 MiB and more) are numpy arrays over recycled
memory: a freed array's block serves the next output of a similar size
(no page faults: the plain call runs at the ``out=`` call's speed, see
benches/README.md). A block is never handed out while an array, or a view
of one, still uses it, and a recycled block's old values never show: each
kernel that takes one writes every element."""

import gc
import os

import numpy as np
import pytest

import mcsample as mcs

N = 1 << 18  # (N, 2) float32 is 2 MiB


def _address(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


def _spoil(a: np.ndarray) -> None:
    """Marks a freed output's memory (all bits set: NaN as floats), so
    that a kernel that leaves an element unwritten shows it."""
    a.view(np.uint8)[...] = 0xFF


def _u(seed: int, dim: int = 2, dtype=np.float32) -> np.ndarray:
    return np.random.default_rng(seed).random((N, dim)).astype(dtype)


def _empty_cache() -> None:
    """Frees what earlier tests left in reference cycles, then empties the
    cache of freed blocks (as every MemoryError mcsample raises does): a
    block freed afterwards is then the only one a request can take. (An
    earlier test's array of another size in range, freed by a later
    ``gc.collect()``, could otherwise serve the request, as it once did
    under pytest-xdist.)"""
    gc.collect()
    with pytest.raises(MemoryError):
        mcs.Rng(1).random(1 << 40)


def test_a_freed_output_is_reused_and_rewritten():
    warp = mcs.warp.square_to_uniform_disk
    _empty_cache()
    first = warp(_u(1))
    assert type(first.base).__name__ == "RecycledBlock"
    address = _address(first)
    _spoil(first)
    del first
    gc.collect()
    u = _u(2)
    second = warp(u)
    assert _address(second) == address
    out = np.zeros_like(second)
    warp(u, out=out)
    np.testing.assert_array_equal(second, out)


def test_live_arrays_and_views_keep_their_memory():
    warp = mcs.warp.square_to_uniform_disk
    a = warp(_u(3))
    view = a[5:10].copy(), a[5:10]
    del a
    gc.collect()
    b = warp(_u(4))
    c = warp(_u(5))
    # The view keeps a's block: neither new array may take it.
    assert len({_address(view[1]) - 5 * 8, _address(b), _address(c)}) == 3
    np.testing.assert_array_equal(view[0], view[1])


@pytest.mark.parametrize("case", ["sphere f64", "envmap sample", "envmap pdf", "envmap eval",
                                  "discrete", "rng", "qmc", "uniform"])
def test_plain_calls_over_recycled_blocks_equal_fresh_results(case):
    """Each family of kernels, called after an output of the same size (of
    other values) was freed, returns what a fresh computation returns."""
    env = mcs.EnvMap()

    def d(s):
        return np.array(mcs.warp.square_to_uniform_sphere(_u(s)), copy=True)

    calls = {
        "sphere f64": lambda s: mcs.warp.square_to_uniform_sphere(_u(s, dtype=np.float64)),
        "envmap sample": lambda s: env.sample(_u(s)).direction,
        "envmap pdf": lambda s: env.pdf(d(s)),
        "envmap eval": lambda s: env.eval(d(s)),
        "discrete": lambda s: mcs.Discrete1D(np.arange(1.0, 50.0)).sample(_u(s, 1)[:, 0]),
        "rng": lambda s: mcs.Rng(s).random((N, 4)),
        "qmc": lambda s: mcs.qmc.Sobol(4, seed=s).random(N),
        "uniform": lambda s: mcs.uniform(N, 4, seed=s),
    }
    call = calls[case]
    for seed in (7, 8):
        expected = np.array(call(seed), copy=True)
        garbage = call(seed + 100)  # another output of the same size, then freed
        _spoil(garbage)
        del garbage
        gc.collect()
        np.testing.assert_array_equal(call(seed), expected)


def test_results_of_more_than_32_dimensions_are_refused():
    """rust-numpy reads at most 32 dimensions: 32 work, 33 are a
    ValueError (it was a panic)."""
    a = mcs.Rng(1).random((1,) * 31 + (N,))
    assert a.shape == (1,) * 31 + (N,) and ((a >= 0) & (a < 1)).all()
    with pytest.raises(ValueError, match="at most 32"):
        mcs.Rng(1).random((1,) * 33 + (N,))


def _vm_flags(address: int) -> list[str]:
    """The VmFlags of the memory mapping that holds ``address`` in this
    process (Linux's /proc/self/smaps)."""
    inside = False
    with open("/proc/self/smaps", errors="replace") as smaps:
        for line in smaps:
            head = line.split()[0]
            if "-" in head and not head.endswith(":"):
                start, end = (int(x, 16) for x in head.split("-"))
                inside = start <= address < end
            elif inside and head == "VmFlags:":
                return line.split()[1:]
    raise AssertionError(f"no mapping holds {address:#x}")


@pytest.mark.skipif(not (os.path.exists("/proc/self/smaps")
                         and os.path.exists("/sys/kernel/mm/transparent_hugepage/enabled")),
                    reason="reads Linux's /proc/self/smaps, on a kernel with transparent huge pages")
def test_large_outputs_are_advised_to_use_huge_pages():
    # As numpy advises its own large arrays (the inputs and out= arrays a
    # plain call's output is written beside): an output of 4 KiB pages made
    # the plain call 5-50 % slower than out= (benches/README.md).
    _empty_cache()
    fresh = mcs.warp.square_to_uniform_disk(_u(5))
    assert type(fresh.base).__name__ == "RecycledBlock"
    assert "hg" in _vm_flags(_address(fresh))
    address = _address(fresh)
    del fresh
    gc.collect()
    recycled = mcs.warp.square_to_uniform_disk(_u(6))
    assert _address(recycled) == address
    assert "hg" in _vm_flags(address)
