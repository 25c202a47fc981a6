"""``mcs.distributed.render`` on a Dask LocalCluster of 2 worker processes:
the bits of a local render for any chunking, a worker killed mid-run
recomputed without changing them, Ctrl-C cancelling the chunks left."""

from __future__ import annotations

import os
import signal
import time

import numpy as np
import pytest

import mcsample as mcs
from mcsample.demo import demo_scene

distributed = pytest.importorskip("distributed")

#: One cluster: under pytest-xdist's ``--dist loadgroup`` (scripts/test.sh)
#: this file's tests run in one worker.
pytestmark = pytest.mark.xdist_group("dask cluster")

FIELDS = ("image", "variance", "luminance_variance")


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    with cluster, distributed.Client(cluster) as c:
        yield c


@pytest.fixture(scope="module")
def scene():
    return mcs.Scene.from_mitsuba(demo_scene(48, 20))


def assert_same_bits(a, b):
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name).view(np.uint32),
                                      getattr(b, name).view(np.uint32), err_msg=name)


@pytest.mark.parametrize("chunks", [None, 3, [1, 2, 5, 16]])
@pytest.mark.parametrize("kw", [dict(integrator="path"),
                                dict(integrator="direct", sampler="sobol", strategy="bsdf")])
def test_the_bits_of_a_local_render(client, scene, chunks, kw):
    local = mcs.render(scene, 24, seed=9, progress=False, **kw)
    remote = mcs.distributed.render(scene, 24, client, chunks, seed=9, progress=False, **kw)
    assert_same_bits(remote, local)
    assert (remote.spp, remote.first_sample) == (24, 0)
    # It keeps its sums: an independent render continues with more samples
    # (sobol's patterns span total_spp, 24 there and 32 here: refused).
    more = mcs.render(scene, 8, seed=9, first_sample=24, total_spp=32, progress=False, **kw)
    if kw.get("sampler") == "sobol":
        with pytest.raises(ValueError, match="different renders"):
            mcs.RenderResult.merge([remote, more])
    else:
        assert_same_bits(mcs.RenderResult.merge([remote, more]),
                         mcs.render(scene, 32, seed=9, progress=False, **kw))


def test_an_in_process_cluster_leaves_the_thread_count(scene):
    """Workers in this process share its thread pool: its size stays."""
    before = mcs.get_num_threads()
    mcs.set_num_threads(2)
    try:
        with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                      dashboard_address=None) as cluster, \
                distributed.Client(cluster) as c:
            remote = mcs.distributed.render(scene, 8, c, 2, seed=5, progress=False)
        assert mcs.get_num_threads() == 2
        assert_same_bits(remote, mcs.render(scene, 8, seed=5, progress=False))
    finally:
        mcs.set_num_threads(before)


def test_chunk_sizes_are_aligned_blocks():
    for spp in range(1, 200):
        for n in (1, 2, 3, 8, 50):
            sizes = mcs.distributed.chunk_sizes(spp, n)
            assert sum(sizes) == spp
            first = 0
            for s in sizes:
                assert s & (s - 1) == 0 and first % s == 0, (spp, n, sizes)
                first += s
    assert mcs.distributed.chunk_sizes(100, 4) == [32, 32, 32, 4]


def test_a_worker_lost_mid_run_changes_nothing(client, scene, monkeypatch):
    """When the first chunk arrives, one worker process is killed (SIGKILL)
    with chunks queued and running on it; Dask reruns them on the other
    worker and on the one its nanny restarts."""
    kw = dict(integrator="path", seed=3)
    local = mcs.render(scene, 256, progress=False, **kw)
    pids = client.run(os.getpid)
    victim = sorted(pids)[0]
    killed = []

    def progress_bar(total, enabled):
        def update(done):
            if not killed:
                # Chunks queued or running on it: their work must be redone.
                killed.append(len(client.processing(workers=[victim])[victim]))
                os.kill(pids[victim], signal.SIGKILL)
        return update, None

    monkeypatch.setattr(mcs.distributed, "_progress_bar", progress_bar)
    remote = mcs.distributed.render(scene, 256, client, [8] * 32, **kw)
    assert killed and killed[0] > 0
    assert_same_bits(remote, local)
    client.wait_for_workers(2, timeout=60)
    assert pids[victim] not in client.run(os.getpid).values()


def test_ctrl_c_cancels_the_chunks(client, scene, monkeypatch, sigint_interrupts):
    """Ctrl-C (SIGINT to this process) when the first chunk arrives: the
    render raises KeyboardInterrupt and the workers drop the rest."""
    def progress_bar(total, enabled):
        return (lambda done: signal.raise_signal(signal.SIGINT)), None

    monkeypatch.setattr(mcs.distributed, "_progress_bar", progress_bar)
    with pytest.raises(KeyboardInterrupt) as interrupted:
        mcs.distributed.render(scene, 4096, client, 64, seed=1)
    # Cancelled, although the traceback still holds the futures.
    assert interrupted.traceback and not client.futures
    deadline = time.monotonic() + 30
    while any(client.processing().values()) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(client.processing().values()), client.processing()


def test_bad_arguments(client, scene):
    with pytest.raises(ValueError, match="add up to"):
        mcs.distributed.render(scene, 10, client, [4, 4], progress=False)
    with pytest.raises(TypeError, match="first_sample"):
        mcs.distributed.render(scene, 10, client, first_sample=2, progress=False)
    with pytest.raises(ValueError, match="spp"):
        mcs.distributed.render(scene, 0, client, progress=False)
    with pytest.raises(ValueError, match="strategy"):
        mcs.distributed.render(scene, 4, client, 2, strategy="nope", progress=False)


@pytest.mark.parametrize("chunks", [None, 3, [16384, 32768, 1000]])
def test_estimates_on_the_cluster_have_the_bits_of_one_run(client, chunks):
    env = mcs.EnvMap()
    n = 3 * 16384 + 1000
    local = mcs.estimators.irradiance(env, [0, 1, 0.2], n, seed=4, sampler="sobol")
    remote = mcs.distributed.estimate(mcs.estimators.irradiance, env, [0, 1, 0.2], n=n,
                                      client=client, chunks=chunks, seed=4, sampler="sobol",
                                      progress=False)
    np.testing.assert_array_equal(remote.value, local.value)
    np.testing.assert_array_equal(remote.stderr, local.stderr)
    assert remote.n == n and remote.mergeable
    phong = mcs.Phong([0.2] * 3, [0.5] * 3, 30.0)
    args = (env, phong, [0, 1, 0], [0.3, 0.9, 0])
    local = mcs.estimators.reflected_radiance(*args, 40000, seed=1)
    remote = mcs.distributed.estimate(mcs.estimators.reflected_radiance, *args, n=40000,
                                      client=client, chunks=2,
                                      seed=1, progress=False)
    np.testing.assert_array_equal(remote.value, local.value)


def test_bad_estimate_chunks(client):
    env = mcs.EnvMap()
    with pytest.raises(ValueError, match="multiples of 16384"):
        mcs.distributed.estimate(mcs.estimators.irradiance, env, [0, 1, 0], n=20000,
                                 client=client, chunks=[10000, 10000], progress=False)
    with pytest.raises(TypeError, match="total_n"):
        mcs.distributed.estimate(mcs.estimators.irradiance, env, [0, 1, 0], n=20000,
                                 client=client, total_n=5, progress=False)
