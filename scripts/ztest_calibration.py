"""How often ``stats.render_ztest`` rejects two unbiased renders (its false
alarm rate), and how often it finds a planted error (its power), on the
README's scene: ``demo_scene(240, 90)`` (Phong spheres of rising exponent
under the packaged sky with its sun), direct lighting, mcsample's MIS
against Mitsuba 3's.

For each spp and each of ``--pairs`` seed pairs: mcsample with seed k
against Mitsuba with seed 1000 + k (false alarm when the test fails); the
same mcsample render made 2 % brighter on its lit (noisy) pixels only,
where a bias in the light's estimate would show (the directly seen sky,
compared by value, would find any change there at once); and mcsample
rendering the sky shifted by one texel (power against an error in the
light's placement). Run on demand (not in CI):

    python scripts/ztest_calibration.py [--pairs 200] [--spp 4 16 256]
"""

from __future__ import annotations

import argparse
import dataclasses
import math

import numpy as np

import mcsample as mcs
from mcsample import stats
from mcsample.demo import demo_scene


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The 95 % Wilson interval of a proportion k / n."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def rate(k: int, n: int) -> str:
    lo, hi = wilson(k, n)
    return f"{k}/{n} = {k / n:.3f} [{lo:.3f}, {hi:.3f}]"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=200)
    parser.add_argument("--spp", type=int, nargs="+", default=[4, 16, 256])
    args = parser.parse_args()
    d = demo_scene(240, 90)
    scene = mcs.Scene.from_mitsuba(d)
    sky = d["sky"]
    shifted = mcs.Scene.from_mitsuba(dict(d, sky=mcs.EnvMap(np.roll(sky.image, 1, axis=1))))
    print(f"stats.render_ztest (block 8, alpha 1e-3), demo_scene(240, 90), direct, MIS; "
          f"Mitsuba {mcs.mitsuba.load().__version__} ({mcs.mitsuba.choose_variant()})")
    for spp in args.spp:
        alarms = biased = moved = 0
        relative_se = []
        for k in range(args.pairs):
            ours = mcs.render(scene, spp, integrator="direct", seed=k, progress=False)
            ref = mcs.mitsuba.render_reference(scene, spp, seed=1000 + k, integrator="direct")
            t = stats.render_ztest(ours, ref)
            relative_se.append(t.relative_se)
            alarms += not t.passed
            # Noisy pixels, as render_ztest tells them from noise-free ones.
            lit = (np.sqrt(ours.luminance_variance) > 1e-4 * ours.luminance)[..., None]
            factor = np.where(lit, 1.02, 1.0)
            brighter = dataclasses.replace(
                ours, image=(ours.image * factor).astype(np.float32),
                luminance_variance=ours.luminance_variance * factor[..., 0] ** 2)
            biased += not stats.render_ztest(brighter, ref).passed
            other = mcs.render(shifted, spp, integrator="direct", seed=k, progress=False)
            moved += not stats.render_ztest(other, ref).passed
        print(f"{spp:4d} spp: false alarms {rate(alarms, args.pairs)}; 2 % brighter where lit found "
              f"{rate(biased, args.pairs)}; sky one texel over found {rate(moved, args.pairs)}; "
              f"median relative SE of the image mean {np.median(relative_se):.2%}", flush=True)


if __name__ == "__main__":
    main()
