"""Command line: ``python -m mcsample demo | render | compare | bench``."""

from __future__ import annotations

import argparse
import os
import sys

#: The benchmark suites (``mcsample.bench.SUITES``), listed here so that
#: the command line does not import the benchmarks to parse its arguments.
SUITE_NAMES = ("rng", "warps", "distr", "phong", "envmap", "render", "convergence", "qmc",
               "samplers", "bidirectional", "meshes")


def _int(low: int, high: int | None = None):
    """An argparse type: an integer in [low, high], refused up front
    otherwise (so that every accepted value works)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if value < low or (high is not None and value > high):
            bound = f"from {low} to {high}" if high is not None else f">= {low}"
            raise argparse.ArgumentTypeError(f"{value}: must be {bound}")
        return value
    return parse


SEED = _int(0, 2**64 - 1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mcsample",
                                     description="mcsample: Monte Carlo sampling toolkit")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="render the demo scene by each strategy (and Mitsuba), "
                                       "and draw the samplers next to their densities")
    demo.add_argument("-o", "--out", default="mcsample-demo", help="output folder")
    demo.add_argument("-n", type=_int(1000), default=1_000_000,
                      help="samples per sampler (>= 1000)")
    demo.add_argument("--spp", type=_int(2), default=32,
                      help="samples per pixel per strategy (>= 2: the comparison with Mitsuba "
                           "needs each pixel's variance)")
    demo.add_argument("--seed", type=SEED, default=0)
    rend = sub.add_parser("render", help="render a scene dict saved as JSON")
    rend.add_argument("scene", help="JSON file: a Mitsuba scene dict (paths relative to it)")
    rend.add_argument("-o", "--out", default="render.exr", help="output .exr (a .png is "
                      "written beside it)")
    rend.add_argument("--spp", type=_int(1), default=None)
    rend.add_argument("--integrator", choices=["direct", "path", "ptracer", "bdpt"], default=None)
    rend.add_argument("--strategy", choices=["bsdf", "emitter", "mis"], default="mis")
    rend.add_argument("--heuristic", choices=["balance", "power"], default="power")
    rend.add_argument("--max-depth", type=_int(-1, 2**32 - 1), default=None,
                      help="-1: unbounded")
    rend.add_argument("--seed", type=SEED, default=0)
    comp = sub.add_parser("compare", help="metrics of an image against a reference")
    comp.add_argument("image")
    comp.add_argument("reference")
    comp.add_argument("-o", "--out", default=None, help="error image (.png; default: "
                      "<image>_error.png)")
    bench = sub.add_parser("bench", help="throughput vs numpy and Mitsuba 3")
    bench.add_argument("-n", type=_int(1000), default=10_000_000, help="samples per call")
    bench.add_argument("--repeat", type=_int(1), default=7)
    bench.add_argument("--only", nargs="*", choices=SUITE_NAMES,
                       help="suites to run (default: all)")
    args = parser.parse_args(argv)

    if args.command == "demo":
        from .demo import run, run_render

        paths, lines = run_render(args.out, spp=args.spp, seed=args.seed)
        print("\n".join(lines))
        paths += run(args.out, n=args.n, seed=args.seed)
        print("wrote:")
        for p in paths:
            print("  " + os.path.abspath(p))
    elif args.command == "render":
        from .cli import render_json

        for p in render_json(args.scene, args.out, spp=args.spp, integrator=args.integrator,
                             strategy=args.strategy, heuristic=args.heuristic,
                             max_depth=args.max_depth, seed=args.seed):
            print("wrote " + os.path.abspath(p))
    elif args.command == "compare":
        from .cli import compare_images

        print(compare_images(args.image, args.reference, args.out))
    elif args.command == "bench":
        from .bench import main as bench_main

        bench_main(n=args.n, repeat=args.repeat, only=args.only)
    return 0


if __name__ == "__main__":
    sys.exit(main())
