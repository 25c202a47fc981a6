"""Makes mcsample's packaged sky, ``python/mcsample/data/sky.exr``.

A lat-long map in Mitsuba's envmap convention (Y up, u = 0 at -Z, u = 1/4 at
+X), 256 x 128 half-float RGB:

- sky: the CIE standard clear sky's relative luminance (Perez's form,
  L(theta, gamma) = (1 + a e^(b / cos theta)) (1 + c e^(d gamma) + e cos^2
  gamma) with a, b, c, d, e = -1, -0.32, 10, -3, 0.45), blue at the zenith,
  paler toward the horizon and the sun;
- sun: a disk of 3 degrees at 35 degrees elevation, of radiance 3000;
- ground: a dark grey (0.04) below the horizon.

Every texel is the mean of 8 x 8 points around its centre, so the sun's rim
is anti-aliased. Run: ``python scripts/make_sky.py`` (needs only numpy and
mcsample).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import mcsample as mcs

WIDTH, HEIGHT = 256, 128
SUN_ELEVATION = np.radians(35.0)
SUN_U = 0.375  # azimuth as Mitsuba's u: between +X (1/4) and +Z (1/2)
SUN_RADIUS = np.radians(1.5)
SUN_RADIANCE = np.array([3000.0, 2900.0, 2600.0])
GROUND = np.array([0.04, 0.04, 0.035])
ZENITH_COLOUR = np.array([0.25, 0.45, 1.0])
HORIZON_COLOUR = np.array([0.85, 0.9, 1.0])
SUPERSAMPLE = 8


def direction(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Mitsuba's lat-long (u, v) -> unit direction."""
    theta, phi = np.pi * v, 2 * np.pi * u
    return np.stack([np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)], -1)


def radiance(d: np.ndarray) -> np.ndarray:
    sun = direction(np.array(SUN_U), np.array(0.5 - SUN_ELEVATION / np.pi))
    cos_gamma = np.clip(d @ sun, -1.0, 1.0)
    gamma = np.arccos(cos_gamma)
    cos_theta = d[..., 1]
    above = cos_theta > 0
    safe = np.maximum(cos_theta, 1e-3)
    gradation = 1 - np.exp(-0.32 / safe)
    indicatrix = 1 + 10 * np.exp(-3 * gamma) + 0.45 * cos_gamma**2
    zenith_norm = (1 - np.exp(-0.32)) * (1 + 10 * np.exp(-3 * (np.pi / 2 - SUN_ELEVATION))
                                         + 0.45 * np.sin(SUN_ELEVATION) ** 2)
    luminance = gradation * indicatrix / zenith_norm
    blend = np.clip(1 - cos_theta, 0, 1)[..., None] ** 2
    colour = (1 - blend) * ZENITH_COLOUR + blend * HORIZON_COLOUR
    sky = 0.6 * luminance[..., None] * colour
    out = np.where(above[..., None], sky, GROUND)
    return np.where((gamma < SUN_RADIUS)[..., None], SUN_RADIANCE, out)


def make() -> np.ndarray:
    # Texel (x, y) sits at u = (x + 1/2) / W, v = y / (H - 1); average over
    # the cell of that size around it.
    offsets = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE - 0.5
    x = np.arange(WIDTH)[None, :, None, None]
    y = np.arange(HEIGHT)[:, None, None, None]
    u = (x + 0.5 + offsets[None, None, :, None]) / WIDTH
    v = np.clip((y + offsets[None, None, None, :]) / (HEIGHT - 1), 0, 1)
    u, v = np.broadcast_arrays(u, v)
    return radiance(direction(u, v)).mean(axis=(2, 3)).astype(np.float32)


def main() -> None:
    image = make()
    path = Path(__file__).resolve().parent.parent / "python" / "mcsample" / "data" / "sky.exr"
    mcs.io.write_exr(path, image, half=True)
    print(f"{path}: {image.shape}, min {image.min():.4g}, max {image.max():.4g}, "
          f"dynamic range {image.max() / image.min():.3g}, {path.stat().st_size} bytes")


if __name__ == "__main__":
    main()
