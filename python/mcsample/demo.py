"""``python -m mcsample demo``: the built-in scene (Phong spheres of rising
exponent on a ground plane under the packaged sky) rendered by BSDF, emitter
and MIS sampling at equal spp, with a Mitsuba 3 render beside them when
Mitsuba is installed; and the built-in samplers drawn next to their
densities, each with its chi-square test."""

from __future__ import annotations

import os
from typing import Callable, NamedTuple

import numpy as np

from . import stats, warp


class Sampler(NamedTuple):
    name: str
    sample: Callable[[np.ndarray], np.ndarray]
    pdf: Callable[[np.ndarray], np.ndarray]
    domain: str
    ires: int = 4


SAMPLERS = [
    Sampler("uniform disk (polar)", warp.square_to_uniform_disk,
            warp.square_to_uniform_disk_pdf, "disk"),
    Sampler("uniform disk (concentric)", warp.square_to_uniform_disk_concentric,
            warp.square_to_uniform_disk_concentric_pdf, "disk"),
    Sampler("uniform triangle", warp.square_to_uniform_triangle,
            warp.square_to_uniform_triangle_pdf, "square", 16),
    Sampler("uniform sphere", warp.square_to_uniform_sphere,
            warp.square_to_uniform_sphere_pdf, "sphere"),
    Sampler("cosine hemisphere", warp.square_to_cosine_hemisphere,
            warp.square_to_cosine_hemisphere_pdf, "hemisphere"),
    Sampler("cosine-power lobe, n = 10",
            lambda u: warp.square_to_cosine_power_hemisphere(u, 10.0),
            lambda d: warp.square_to_cosine_power_hemisphere_pdf(d, 10.0), "hemisphere", 8),
    Sampler("uniform cone, cos cutoff 0.5", lambda u: warp.square_to_uniform_cone(u, 0.5),
            lambda d: warp.square_to_uniform_cone_pdf(d, 0.5), "hemisphere"),
    Sampler("power distribution (n+1) x^n, n = 3",
            lambda u: warp.interval_to_power(u[:, 0], 3.0),
            lambda x: warp.interval_to_power_pdf(x, 3.0), "interval"),
]


def run(out_dir: str = "mcsample-demo", n: int = 1_000_000, seed: int = 0) -> list[str]:
    """Draws ``n`` samples from each built-in sampler, tests them against
    their pdf, and writes ``samplers.png`` (per row: samples, histogram,
    expected counts, difference) into ``out_dir``. Returns the paths
    written."""
    from matplotlib.figure import Figure

    from . import plot

    os.makedirs(out_dir, exist_ok=True)
    rows = len(SAMPLERS)
    fig = Figure(figsize=(17, 3.4 * rows), layout="constrained")
    axes = fig.subplots(rows, 4, squeeze=False)
    lines = []
    for row, s in zip(axes, SAMPLERS):
        result = stats.chi2_test(s.sample, s.pdf, s.domain, n=n, ires=s.ires, seed=seed,
                                 test_count=len(SAMPLERS))
        verdict = "passed" if result.passed else "FAILED"
        lines.append(f"{s.name:40s} chi2 p-value {result.p_value:8.4f}  {verdict}")
        u = np.random.default_rng(seed).random((3000, 2))
        plot.samples(s.sample(u), s.domain, ax=row[0])
        row[0].set_title(f"{s.name}\n3000 samples")
        plot.chi2(result, axes=row[1:])
    path = os.path.join(out_dir, "samplers.png")
    fig.savefig(path, dpi=70)
    report = os.path.join(out_dir, "chi2.txt")
    with open(report, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    return [path, report]


def demo_scene(width: int = 320, height: int = 120) -> dict:
    """The demo scene as a Mitsuba dict: four Phong spheres (exponents 1,
    10, 100, 1000) on a diffuse ground plane under the packaged sky."""
    from . import EnvMap, look_at

    d: dict = {
        "type": "scene",
        "sensor": {"type": "perspective", "fov": 42,
                   "to_world": look_at([0, 1.6, 6.5], [0, 0.45, 0], [0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": width, "height": height,
                            "rfilter": {"type": "box"}}},
        "sky": EnvMap(),
        "ground": {"type": "rectangle",
                   "to_world": np.array([[8.0, 0, 0, 0], [0, 0, 8.0, 0], [0, -8.0, 0, 0],
                                         [0, 0, 0, 1]]),
                   "bsdf": {"type": "diffuse", "reflectance": 0.4}},
    }
    for i, n in enumerate((1, 10, 100, 1000)):
        d[f"sphere_n{n}"] = {
            "type": "sphere", "center": [1.3 * (i - 1.5), 0.5, 0], "radius": 0.5,
            "bsdf": {"type": "mcsample_phong", "diffuse_reflectance": [0.15, 0.1, 0.05],
                     "specular_reflectance": [0.75, 0.75, 0.75], "exponent": float(n)}}
    return d


def run_render(out_dir: str = "mcsample-demo", spp: int = 32, seed: int = 0,
               width: int = 320, height: int = 120) -> tuple[list[str], list[str]]:
    """Renders the demo scene by each strategy at ``spp`` (direct lighting),
    a 16× spp MIS reference, and Mitsuba's image when it is installed; writes
    the EXR and PNG images and ``strategies.png`` (images, relMSE, error
    maps). Returns the paths written and the report lines."""
    from . import Scene, io, plot, render
    from . import mitsuba as mcs_mitsuba

    os.makedirs(out_dir, exist_ok=True)
    scene = Scene.from_mitsuba(demo_scene(width, height))
    ref = render(scene, 16 * spp, integrator="direct", strategy="mis", seed=seed + 1)
    paths, lines = [], []
    results = {}
    for strategy in ("bsdf", "emitter", "mis"):
        r = render(scene, spp, integrator="direct", strategy=strategy, seed=seed)
        results[strategy] = r
        err = stats.relmse(r.image, ref.image)
        lines.append(f"{strategy:8s} {spp} spp  {r.seconds:6.2f} s  relMSE {err:.4g}")
    mitsuba_result = None
    if mcs_mitsuba.available():
        mitsuba_result = mcs_mitsuba.render_reference(scene, spp, seed=seed, integrator="direct")
        t = stats.render_ztest(results["mis"], mitsuba_result)
        lines.append(f"mitsuba  {spp} spp  {mitsuba_result.seconds:6.2f} s  relMSE "
                     f"{stats.relmse(mitsuba_result.image, ref.image):.4g} "
                     f"(z-test of mcsample MIS vs Mitsuba: {t.message.splitlines()[0]})")
    for name, r in list(results.items()) + [("reference", ref)] + (
            [("mitsuba", mitsuba_result)] if mitsuba_result is not None else []):
        for ext, write in ((".exr", io.write_exr), (".png", io.write_png)):
            path = os.path.join(out_dir, f"render_{name}{ext}")
            write(path, r.image)
            paths.append(path)
    shown = dict(results, **({"mitsuba": mitsuba_result} if mitsuba_result else {}))
    fig = plot.compare(shown, ref)
    path = os.path.join(out_dir, "strategies.png")
    fig.savefig(path, dpi=90)
    paths.append(path)
    return paths, lines
