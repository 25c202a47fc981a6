"""Issue 31's table, measured again: mcsample / Mitsuba 3 image-mean
luminance for a diffuse floor (or wall, or room) lit by one area light, by
each strategy alone and by MIS.

Each cell renders the scene with ``--seeds`` seeds × ``--spp`` samples per
pixel on each side (BSDF sampling 4× as many; Mitsuba's ``direct`` or
``path`` integrator with its MIS as the reference for every strategy, since
all are unbiased) and prints the ratio of the mean luminances with its
standard error (from each render's per-pixel variances, on both sides) and
how many standard errors it lies from 1. Run on demand (not in CI):

    python scripts/area_light_table.py [--seeds 16] [--spp 256] [--first-seed 0]
                                       [--only TEXT] [--markdown]

``--first-seed`` measures again with other seeds (mcsample's seeds start
there, Mitsuba's at 1000 more); ``--only`` keeps the rows whose name
contains TEXT.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import mcsample as mcs  # noqa: E402
from scenes import ground, lit_room, sensor, transform  # noqa: E402

DOWN = [("x", 90.0)]  # Mitsuba's flat shapes face +z; this faces them down (-y)


def floor_scene(light: dict, camera=((0.0, 2.0, 2.2), (0.0, 0.0, 0.0))) -> dict:
    return {"type": "scene",
            "sensor": sensor(origin=camera[0], target=camera[1], fov=50.0, width=64,
                             height=48),
            "floor": ground(size=8.0, reflectance=0.6), "light": light}


def emitter(radiance: float) -> dict:
    return {"type": "area", "radiance": radiance}


def wall_scene(turn: float) -> dict:
    """A 0.6 × 0.6 rectangle 1.0 from a wall x = 0 (facing +x), facing it,
    turned by ``turn`` degrees about its own normal."""
    wall = {"type": "rectangle", "to_world": transform((0, 1.5, 0), [("y", 90.0)], (3, 3, 1)),
            "bsdf": {"type": "diffuse", "reflectance": 0.6}}
    light = {"type": "rectangle",
             "to_world": transform((1.0, 1.5, 0.0), [("z", turn), ("y", -90.0)],
                                   (0.3, 0.3, 1.0)),
             "emitter": emitter(10.0)}
    return {"type": "scene",
            "sensor": sensor(origin=(2.6, 1.6, 0.4), target=(0.0, 1.5, 0.0), fov=50.0,
                             width=64, height=48),
            "wall": wall, "light": light}


def cases() -> dict[str, tuple[dict, str]]:
    """The rows of issue 31's table: a scene dict and its integrator."""
    rows = {
        "rectangle 0.2 x 0.2, 0.3 above the floor, facing down": floor_scene(
            {"type": "rectangle", "to_world": transform((0, 0.3, 0), DOWN, (0.1, 0.1, 1)),
             "emitter": emitter(40.0)}),
        "disk radius 0.3, 1.0 above the floor": floor_scene(
            {"type": "disk", "to_world": transform((0, 1.0, 0), DOWN, (0.3, 0.3, 1)),
             "emitter": emitter(20.0)}),
        "sphere radius 0.15 near the floor": floor_scene(
            {"type": "sphere", "center": [0.0, 0.25, 0.0], "radius": 0.15,
             "emitter": emitter(20.0)}),
        "sphere radius 0.4, ~3.3 away": floor_scene(
            {"type": "sphere", "center": [2.0, 2.6, -0.5], "radius": 0.4,
             "emitter": emitter(40.0)}),
        "rectangle 2 x 2, 3 above the floor": floor_scene(
            {"type": "rectangle", "to_world": transform((0, 3.0, 0), DOWN, (1, 1, 1)),
             "emitter": emitter(5.0)}),
    }
    out = {name: (d, "direct") for name, d in rows.items()}
    for turn in (0.0, 30.0, 60.0, 90.0):
        out[f"rectangle 0.6 x 0.6, 1.0 from a wall, turned {turn:g} deg"] = (wall_scene(turn),
                                                                            "direct")
    out["closed room, small light facing the ceiling (path)"] = (lit_room("rectangle"), "path")
    return out


def mean_luminance(scene: mcs.Scene, integrator: str, spp: int, seeds: range,
                   strategy: str | None) -> tuple[float, float]:
    """The image-mean luminance over the seeds' renders (Mitsuba's if
    strategy is None) and its variance, from the pixels' variances."""
    means, variances = [], []
    for seed in seeds:
        if strategy is None:
            r = mcs.mitsuba.render_reference(scene, spp, seed=1000 + seed, integrator=integrator,
                                             hide_emitters=True)
        else:
            r = mcs.render(scene, spp, integrator=integrator, strategy=strategy, seed=seed,
                           hide_emitters=True, progress=False)
        means.append(r.luminance.mean())
        variances.append(r.luminance_variance.sum() / r.luminance.size ** 2)
    return float(np.mean(means)), float(np.sum(variances)) / len(seeds) ** 2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=16)
    parser.add_argument("--spp", type=int, default=256)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--only", default="", help="rows whose name contains this")
    parser.add_argument("--markdown", action="store_true", help="print a markdown table")
    args = parser.parse_args()
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    strategies = ("emitter", "bsdf", "mis")
    print(f"mcsample / Mitsuba {mcs.mitsuba.load().__version__} ({mcs.mitsuba.choose_variant()}),"
          f" {args.seeds} seeds x {args.spp} spp per side (BSDF sampling x4); ratio ± SE "
          "(z = (ratio - 1) / SE)")
    if args.markdown:
        print("| light | " + " | ".join(f'strategy="{s}"' for s in strategies) + " |")
        print("|---|" + "---|" * len(strategies))
    for name, (d, integrator) in cases().items():
        if args.only not in name:
            continue
        scene = mcs.Scene.from_mitsuba(d)
        ref, ref_var = mean_luminance(scene, integrator, args.spp, seeds, None)
        cells = []
        for strategy in strategies:
            spp = 4 * args.spp if strategy == "bsdf" else args.spp
            ours, var = mean_luminance(scene, integrator, spp, seeds, strategy)
            ratio = ours / ref
            se = ratio * np.hypot(np.sqrt(var) / ours, np.sqrt(ref_var) / ref)
            cells.append(f"{ratio:.4f} ± {se:.4f} (z = {(ratio - 1) / se:+.1f})")
        if args.markdown:
            print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
        else:
            print(f"{name}: " + "; ".join(f"{s} {c}" for s, c in zip(strategies, cells)),
                  flush=True)


if __name__ == "__main__":
    main()
