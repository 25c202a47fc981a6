"""Requests too big for memory are a Python error, never a crash: every entry
point that allocates in proportion to its input, run in a subprocess under
an address-space limit (``RLIMIT_AS``, as a container or a busy laptop
gives), raises MemoryError (or ValueError where a size limit applies) with
a message naming the size, and the process is alive and usable afterwards.

Each group of calls runs in one subprocess; a call that aborts the process
(Rust's infallible allocation) or raises anything else fails its group.
"""

from __future__ import annotations

import inspect
import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import mcsample as mcs

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS is Linux's")

#: The address-space limit of the subprocesses: room for Python, numpy and
#: mcsample's threads, far below what each call asks for.
LIMIT = 3 << 30

#: Rows of the big batches: float32 copies of them take 4-12 GiB.
ROWS = 10**9

#: Scalar parameters of the warps that take them, valid values.
WARP_PARAMETERS = {"exponent": 2.0, "cos_cutoff": 0.5, "v0": 1.0, "v1": 2.0,
                   "a": 0.0, "b": 0.5, "c": 1.0, "method": "concentric", "alpha": 0.5,
                   "kappa": 2.0, "wi": [0.0, 0.0, 1.0], "tangent": [1.0, 0.0, 0.0],
                   "n1": [0.0, 0.6, 0.8], "n2": [0.8, 0.6, 0.0], "n": [0.0, 0.0, 1.0],
                   "v00": 1.0, "v10": 2.0, "v01": 3.0, "v11": 4.0}


def _warp_calls() -> list[str]:
    """Each warp on a broadcast (zero-memory) batch of ``ROWS`` points: the
    binding's copy of it, then its output, are too big."""
    calls = []
    for name in sorted(dir(mcs.warp)):
        f = getattr(mcs.warp, name)
        if name.startswith("_") or not callable(f):
            continue
        params = [p for p in inspect.signature(f).parameters if p != "out"]
        points = next(p for p in params if p not in WARP_PARAMETERS)
        for k in (1, 2, 3):  # the points' width: the one the warp accepts
            small = np.full((4, k) if k > 1 else (4,), 0.25)
            try:
                f(**{p: (small if p == points else WARP_PARAMETERS[p]) for p in params})
                break
            except ValueError:
                continue
        shape = (ROWS, k) if k > 1 else (ROWS,)
        args = ", ".join(f"{p}=big({shape})" if p == points else f"{p}={WARP_PARAMETERS[p]!r}"
                         for p in params)
        calls.append(f"mcs.warp.{name}({args})")
    return calls


_PLY_HEADER = ("ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n"
               "property float x\nproperty float y\nproperty float z\n"
               "element face 10\nproperty list uchar int vertex_indices\nend_header\n")

GROUPS: dict[str, list[str]] = {
    "random numbers": [
        "mcs.uniform(10**10, 2)",
        "mcs.uniform(10**9, 3, dtype=np.float32)",
        "mcs.Rng(1).random((10**5, 10**5))",
        "mcs.Rng(1).next_uint32((10**5, 10**5))",
    ],
    "warps": _warp_calls(),
    "distributions": [
        "mcs.Discrete1D(big((ROWS,)))",
        "mcs.AliasTable(big((ROWS,)))",
        "mcs.Discrete2D(big((40000, 40000)))",
        "mcs.PiecewiseConstant1D(big((ROWS,)))",
        "mcs.PiecewiseConstant2D(big((40000, 40000)))",
        "mcs.Discrete1D(np.ones(1000)).sample(big((ROWS,)))",
        "mcs.Discrete1D(np.ones(1000)).pmf(np.broadcast_to(np.int64(3), (ROWS,)))",
        "mcs.Frame(big((ROWS, 3)))",
        "mcs.Frame([0, 0, 1]).to_local(big((ROWS, 3)))",
    ],
    "envmap": [
        # 2**28 texels, the most a map may have: 3 GiB of texels alone.
        "mcs.EnvMap(big((16384, 16384, 3)))",
        "mcs.EnvMap(big((6, 6000, 6000, 3)), mapping='cube')",
        "mcs.EnvMap(np.ones((8192, 16384, 3), np.float32))",
        "mcs.EnvMap(big((8192, 32769, 3)))",  # beyond 2**28: ValueError
        "mcs.EnvMap(np.ones((8, 16, 3), np.float32)).convert('latlong', (16384, 16384))",
        # Faces of 6600²: 3.1 GB of texels, asked for before any is computed
        # (beyond the limit with the process's own address space).
        "mcs.EnvMap(np.ones((8, 16, 3), np.float32)).convert('cube', 6600)",
        "mcs.EnvMap.load(write_hdr(16384, 16384))",
        "mcs.EnvMap.load(write_hdr(40000, 40000))",  # beyond 2**28: ValueError
        "mcs.EnvMap(np.ones((8, 16, 3), np.float32)).sample(big((ROWS, 2)))",
        "mcs.EnvMap(np.ones((8, 16, 3), np.float32)).eval(big((ROWS, 3)))",
        "mcs.EnvMap(np.ones((8, 16, 3), np.float32)).pdf(big((ROWS, 3)))",
    ],
    "materials and estimators": [
        "mcs.Phong(0.3, 0.5, 20).sample([0, 0, 1], big((ROWS, 3)))",
        "mcs.Phong(0.3, 0.5, 20).eval(big((ROWS, 3)), [0, 0, 1])",
        "mcs.estimators.irradiance(mcs.EnvMap(np.ones((8, 16, 3))), [0, 0, 1], 2**40)",
        "mcs.estimators.reflected_radiance(mcs.EnvMap(np.ones((8, 16, 3))), "
        "mcs.Phong(0.3, 0.5, 20), [0, 0, 1], [0, 0, 1], 2**40)",
        "mcs.stats.chi2_test(mcs.warp.square_to_uniform_disk, "
        "mcs.warp.square_to_uniform_disk_pdf, 'disk', n=10**10)",
    ],
    "render": [
        "mcs.render(scene(32768, 32768), 1, progress=False)",
        "mcs.render(scene(4, 4), 2**30, progress=False)",
        "mcs.render(scene(4, 4, mesh=(8, 2 * 10**7)), 1, progress=False)",
        "mcs.render(scene(4, 4, ply=True), 1, progress=False)",
        "mcs.io.read_mesh(write_ply())",
        "mcs.io.read_mesh(write_obj())",
    ],
    "qmc": [
        "mcs.qmc.Sobol(8, seed=1).random(10**9)",
        "mcs.qmc.Halton(8, seed=1).random(10**9)",
        "mcs.qmc.LatinHypercube(8, seed=1).random(10**9)",
        "mcs.qmc.MultiJitter(8, seed=1).random(10**9)",
    ],
}

_RUNNER = textwrap.dedent("""
    import json, os, resource, sys, tempfile
    import numpy as np
    import mcsample as mcs
    ROWS = {rows}
    PLY_HEADER = {ply!r}
    tmp = tempfile.mkdtemp()

    def big(shape):
        return np.broadcast_to(np.float32(0.25), shape)

    def write_hdr(w, h):
        # A Radiance header claiming w x h texels, and no pixels.
        path = os.path.join(tmp, f"{{w}}x{{h}}.hdr")
        with open(path, "wb") as f:
            f.write(f"#?RADIANCE\\nFORMAT=32-bit_rle_rgbe\\n\\n-Y {{h}} +X {{w}}\\n".encode())
        return path

    def write_ply():
        path = os.path.join(tmp, "big.ply")
        with open(path, "wb") as f:
            f.write(PLY_HEADER.encode())
        return path

    def write_obj():
        # A sparse file of 4 GiB (no disk used): too big to read.
        path = os.path.join(tmp, "big.obj")
        with open(path, "wb") as f:
            f.truncate(4 << 30)
        return path

    def scene(w, h, mesh=None, ply=False):
        shape = {{"type": "sphere"}}
        if mesh is not None:
            v, m = mesh
            shape = {{"type": "mesh", "vertices": np.random.default_rng(0).random((v, 3)),
                     "faces": np.broadcast_to(np.array([0, 1, 2]), (m, 3))}}
        if ply:
            shape = {{"type": "ply", "filename": write_ply()}}
        return mcs.Scene.from_mitsuba({{
            "type": "scene", "shape": shape, "env": {{"type": "constant"}},
            "sensor": {{"type": "perspective", "fov": 45,
                        "film": {{"type": "hdrfilm", "width": w, "height": h}}}}}})

    resource.setrlimit(resource.RLIMIT_AS, ({limit}, {limit}))
    for call in json.loads(sys.argv[1]):
        try:
            eval(call)
            outcome = ["returned", ""]
        except BaseException as e:
            outcome = [type(e).__name__, str(e)]
        # Alive and usable: a small call of the same library.
        assert mcs.uniform(4, 2).shape == (4, 2)
        print(json.dumps([call] + outcome), flush=True)
""")


@pytest.mark.parametrize("group", list(GROUPS))
def test_requests_beyond_memory_raise_and_leave_the_process_alive(group: str) -> None:
    calls = GROUPS[group]
    code = _RUNNER.format(rows=ROWS, ply=_PLY_HEADER, limit=LIMIT)
    run = subprocess.run([sys.executable, "-c", code, json.dumps(calls)],
                         capture_output=True, text=True, timeout=600)
    done = [json.loads(line) for line in run.stdout.splitlines() if line.startswith("[")]
    assert run.returncode == 0, (
        f"the process died (code {run.returncode}) after {len(done)} of {len(calls)} "
        f"calls, on {calls[len(done)] if len(done) < len(calls) else '?'}:\n"
        f"{run.stderr[-2000:]}")
    assert len(done) == len(calls)
    for call, kind, message in done:
        assert kind in ("MemoryError", "ValueError"), f"{call}: {kind}: {message}"
        # The message names the size asked for (bytes, or the count and its limit).
        assert any(ch.isdigit() for ch in message), f"{call}: {kind}: {message}"

