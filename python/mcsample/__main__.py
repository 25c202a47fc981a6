"""Command line: ``python -m mcsample demo | render | compare | bench``."""

from __future__ import annotations

import argparse
import os
import sys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mcsample",
                                     description="mcsample: Monte Carlo sampling toolkit")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="render the demo scene by each strategy (and Mitsuba), "
                                       "and draw the samplers next to their densities")
    demo.add_argument("-o", "--out", default="mcsample-demo", help="output folder")
    demo.add_argument("-n", type=int, default=1_000_000, help="samples per sampler")
    demo.add_argument("--spp", type=int, default=32, help="samples per pixel per strategy")
    demo.add_argument("--seed", type=int, default=0)
    rend = sub.add_parser("render", help="render a scene dict saved as JSON")
    rend.add_argument("scene", help="JSON file: a Mitsuba scene dict (paths relative to it)")
    rend.add_argument("-o", "--out", default="render.exr", help="output .exr (a .png is "
                      "written beside it)")
    rend.add_argument("--spp", type=int, default=None)
    rend.add_argument("--integrator", choices=["direct", "path"], default=None)
    rend.add_argument("--strategy", choices=["bsdf", "emitter", "mis"], default="mis")
    rend.add_argument("--heuristic", choices=["balance", "power"], default="power")
    rend.add_argument("--max-depth", type=int, default=None)
    rend.add_argument("--seed", type=int, default=0)
    comp = sub.add_parser("compare", help="metrics of an image against a reference")
    comp.add_argument("image")
    comp.add_argument("reference")
    comp.add_argument("-o", "--out", default=None, help="error image (.png; default: "
                      "<image>_error.png)")
    bench = sub.add_parser("bench", help="throughput vs numpy and Mitsuba 3")
    bench.add_argument("-n", type=int, default=10_000_000, help="samples per call")
    bench.add_argument("--repeat", type=int, default=7)
    bench.add_argument("--only", nargs="*", help="suites to run (default: all)")
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
