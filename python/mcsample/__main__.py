"""Command line: ``python -m mcsample demo | bench``."""

from __future__ import annotations

import argparse
import os
import sys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mcsample",
                                     description="mcsample: Monte Carlo sampling toolkit")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="draw the built-in samplers next to their densities")
    demo.add_argument("-o", "--out", default="mcsample-demo", help="output folder")
    demo.add_argument("-n", type=int, default=1_000_000, help="samples per sampler")
    demo.add_argument("--seed", type=int, default=0)
    bench = sub.add_parser("bench", help="throughput vs numpy and Mitsuba 3")
    bench.add_argument("-n", type=int, default=10_000_000, help="samples per call")
    bench.add_argument("--repeat", type=int, default=7)
    bench.add_argument("--only", nargs="*", help="suites to run (default: all)")
    args = parser.parse_args(argv)

    if args.command == "demo":
        from .demo import run

        paths = run(args.out, n=args.n, seed=args.seed)
        print("wrote:")
        for p in paths:
            print("  " + os.path.abspath(p))
    elif args.command == "bench":
        from .bench import main as bench_main

        bench_main(n=args.n, repeat=args.repeat, only=args.only)
    return 0


if __name__ == "__main__":
    sys.exit(main())
