"""Scaling of ``mcs.distributed.render`` on this machine: wall-clock time
of one reference render (the demo scene, path tracing, MIS) in one process
(``mcs.render``, all cores) and on Dask LocalClusters of processes x
threads, each merged to the same bits. Run on demand:

    python benches/dask_scaling.py [--spp 1024] [--size 320x120] [--rounds 3]

Prints a Markdown table (the README's "Renders in chunks and on a
cluster" quotes it): median seconds over the rounds, M samples/s, and the
speed relative to the single process.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np
from distributed import Client, LocalCluster

import mcsample as mcs
from mcsample.demo import demo_scene


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--size", default="320x120")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    width, height = map(int, args.size.split("x"))
    scene = mcs.Scene.from_mitsuba(demo_scene(width, height))
    kw = dict(integrator="path", seed=1, progress=False)
    cores = os.cpu_count() or 1
    samples = args.spp * width * height

    def timed(run) -> tuple[float, mcs.RenderResult]:
        times, result = [], None
        for _ in range(args.rounds):
            start = time.perf_counter()
            result = run()
            times.append(time.perf_counter() - start)
        return statistics.median(times), result

    base, local = timed(lambda: mcs.render(scene, args.spp, **kw))
    rows = [(f"one process, {cores} threads (`mcs.render`)", base)]
    layouts = sorted({(1, cores), (cores, 1), (2, max(1, cores // 2))})
    for workers, threads in layouts:
        with LocalCluster(n_workers=workers, threads_per_worker=threads, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            mcs.distributed.render(scene, 16, client, **kw)  # workers warm, scene compiled
            seconds, result = timed(lambda: mcs.distributed.render(scene, args.spp, client, **kw))
        assert np.array_equal(result.image, local.image), "not the bits of one render"
        rows.append((f"LocalCluster {workers} x {threads}", seconds))
    print(f"{width} x {height}, {args.spp} spp, path tracing, MIS; {cores} cores; "
          f"median of {args.rounds}")
    print("| layout | seconds | M samples/s | vs one process |")
    print("|---|---|---|---|")
    for name, seconds in rows:
        print(f"| {name} | {seconds:.2f} | {samples / seconds / 1e6:.1f} | "
              f"{base / seconds:.2f} |")


if __name__ == "__main__":
    main()
