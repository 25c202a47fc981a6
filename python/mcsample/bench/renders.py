"""Render suites: samples per second, time to a given error, and the
samplers (speed, and relMSE at equal spp beside Mitsuba's samplers)."""

from __future__ import annotations

import numpy as np

import mcsample as mcs

from .timing import Timing, measure, measure_side_by_side


def _render_scenes(size: int = 256) -> dict[str, dict]:
    """The issue's two speed scenes: a diffuse sphere under the packaged sky,
    and a sphere on a plane lit by the sky and a rectangular area light."""
    sensor = {"type": "perspective", "fov": 35,
              "to_world": mcs.look_at([0, 1.2, 4.5], [0, 0.6, 0], [0, 1, 0]),
              "film": {"type": "hdrfilm", "width": size, "height": size,
                       "rfilter": {"type": "box"}}}
    ball = {"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6,
            "bsdf": {"type": "diffuse", "reflectance": [0.7, 0.6, 0.5]}}
    floor = {"type": "rectangle", "bsdf": {"type": "diffuse", "reflectance": 0.5},
             "to_world": np.array([[4.0, 0, 0, 0], [0, 0, 4.0, 0], [0, -4.0, 0, 0], [0, 0, 0, 1]])}
    light = {"type": "rectangle", "emitter": {"type": "area", "radiance": [12.0, 11.0, 9.0]},
             "to_world": np.array([[0.4, 0, 0, 1.0], [0, 0, 1, 2.0], [0, -0.4, 0, 0.8],
                                   [0, 0, 0, 1]])}
    sky = mcs.EnvMap()
    return {
        "sphere under sky": {"type": "scene", "sensor": sensor, "sky": sky, "ball": ball},
        "sphere on plane": {"type": "scene", "sensor": sensor, "sky": sky, "ball": ball,
                            "floor": floor, "light": light},
    }


def suite_render(n: int, repeat: int, mi, spp: int = 64) -> list[Timing]:
    """Samples (camera paths) per second at 256 x 256, 64 spp, MIS, direct and
    path; Mitsuba's time excludes its JIT compilation (warm-up renders)."""
    out = []
    repeat = min(repeat, 3)
    for name, d in _render_scenes().items():
        scene = mcs.Scene.from_mitsuba(d)
        h, w = scene.shape
        samples = w * h * spp
        mi_scene = None
        if mi is not None:
            mi_scene = mi.load_dict(scene.to_mitsuba(spp=spp))
        for integrator in ("direct", "path"):
            case = f"render {name}, {integrator}"
            runs = [("mcsample", lambda: mcs.render(scene, spp, integrator=integrator,
                                                    progress=False))]
            if mi_scene is not None:
                mi_int = mi.load_dict({"type": integrator})

                def run_mitsuba():
                    img = mi.render(mi_scene, integrator=mi_int, spp=spp)
                    np.asarray(img)
                runs.append(("mitsuba llvm_ad_rgb", run_mitsuba))
            # Side by side, after two warm-up renders of each (Mitsuba's JIT).
            seconds = measure_side_by_side([r[1] for r in runs], repeat, 2)
            out += [Timing(case, impl, "float32", samples, t)
                    for (impl, _), t in zip(runs, seconds)]
    return out


def suite_convergence(n: int, repeat: int, mi, target: float = 0.01, spp: int = 16,
                      ref_spp: int = 512) -> list[Timing]:
    """Time to reach relMSE ``target`` on the demo scene (Phong spheres of
    exponent 1 to 1000 under the packaged sky, 240 x 90, direct lighting),
    by each strategy and by Mitsuba's MIS.

    relMSE falls as C / spp for an unbiased renderer, so C is measured at
    ``spp`` against a ``ref_spp`` MIS reference (less the reference's own
    share, measured between two independent references), and the time to
    the target is (C / target) spp at the measured seconds per spp. The
    "samples" column is the pixel samples that takes."""
    from ..demo import demo_scene

    scene = mcs.Scene.from_mitsuba(demo_scene(240, 90))
    ours = {f"mcsample {s}": {"integrator": "direct", "strategy": s}
            for s in ("bsdf", "emitter", "mis")}
    return _time_to_relmse(scene, ours, ours["mcsample mis"], ("MIS", {"type": "direct"}),
                           (mi, repeat), (target, "demo"), (spp, ref_spp))


#: Images per renderer whose relMSE :func:`_time_to_relmse` averages.
IMAGES = 8


def _time_to_relmse(scene: mcs.Scene, ours: dict[str, dict], reference: dict,
                    mitsuba: tuple[str, dict], runner: tuple, case: tuple[float, str],
                    counts: tuple[int, int]) -> list[Timing]:
    """Each render's time to relMSE ``target`` on ``scene``: mcsample's
    renders with the keywords of ``ours`` (name → keywords) and, with
    ``mi``, Mitsuba's with the integrator ``mitsuba`` = (label, dict).
    relMSE falls as C / spp for an unbiased renderer, so C is measured at
    ``spp`` against a ``ref_spp`` reference rendered with ``reference``
    (less the reference's own share, measured between two independent
    references), and the time to the target is (C / target) spp at the
    measured seconds per spp; the "samples" column is the pixel samples
    that takes. C is the mean over ``IMAGES`` images of each renderer (of
    seeds of their own): one image's relMSE at 16 spp moves by 20 % from
    seed to seed."""
    (mi, repeat), (target, name), (spp, ref_spp) = runner, case, counts
    h, w = scene.shape

    def render(keywords: dict, count: int, seed: int):
        return mcs.render(scene, count, seed=seed, progress=False, **keywords)

    ref_a, ref_b = render(reference, ref_spp, 1), render(reference, ref_spp, 2)
    floor = mcs.stats.relmse(ref_a.image, ref_b.image) / 2
    runs: dict[str, tuple[list[np.ndarray], float]] = {}
    for label, keywords in ours.items():
        seconds = measure(lambda keywords=keywords: render(keywords, spp, 3), repeat, 1)
        runs[label] = ([render(keywords, spp, 4 + k).image for k in range(IMAGES)], seconds)
    if mi is not None:
        exported = scene.to_mitsuba(spp=spp)
        variants = [("", exported)]
        # Mitsuba's MIS draws an envmap by its own density unless told to
        # compensate, as mcsample's MIS does by itself: both are timed.
        envmaps = [k for k, v in exported.items() if isinstance(v, dict) and v.get("type") == "envmap"]
        if envmaps:
            variants.append((", compensated", {
                **exported, **{k: {**exported[k], "mis_compensation": True} for k in envmaps}}))
        mi_int = mi.load_dict(mitsuba[1])
        for suffix, scene_dict in variants:
            mi_scene = mi.load_dict(scene_dict)
            seconds = measure(lambda: np.asarray(mi.render(mi_scene, integrator=mi_int, spp=spp)),
                              repeat, 2)
            images = [np.asarray(mi.render(mi_scene, integrator=mi_int, spp=spp, seed=5 + k))
                      for k in range(IMAGES)]
            runs[f"Mitsuba 3 llvm ({mitsuba[0]}{suffix})"] = ([i[..., :3] for i in images],
                                                               seconds)
    out = []
    for label, (images, seconds) in runs.items():
        relmse = float(np.mean([mcs.stats.relmse(image, ref_a.image) for image in images]))
        needed = max(relmse - floor, 1e-12) * spp / target
        out.append(Timing(f"time to relMSE {target:g}, {name}", label, "float32",
                          int(needed * w * h), needed * seconds / spp))
    return out


SAMPLERS = ("independent", "stratified", "multijitter", "sobol", "ldsampler", "zsobol")
#: Mitsuba's samplers beside mcsample's equivalents.
MITSUBA_SAMPLERS = {"independent": "independent", "stratified": "stratified",
                    "multijitter": "multijitter", "ldsampler": "ldsampler"}


def sampler_relmse(mi, spp_list=(16, 64), seeds: int = 4, ref_spp: int = 4096,
                   size: tuple[int, int] = (60, 160)) -> list[tuple[int, str, float, float | None]]:
    """relMSE of the demo scene (direct, MIS) at equal spp by each of
    mcsample's samplers and Mitsuba's equivalent, each against a
    ``ref_spp`` render of its own renderer (mean over ``seeds``). The sky
    is sampled by Mitsuba's density on both sides, compensated as MIS
    renders draw a map (``EnvMap(sampling="mitsuba", compensate=True)``,
    Mitsuba's ``mis_compensation``), so that the integrands are the same
    and only the samplers differ. Rows: (spp, sampler, mcsample relMSE,
    Mitsuba's or None)."""
    from ..demo import demo_scene

    d = demo_scene(size[1], size[0])
    d["sky"] = mcs.EnvMap(sampling="mitsuba", compensate=True)
    scene = mcs.Scene.from_mitsuba(d)
    ours_ref = mcs.render(scene, ref_spp, integrator="direct", seed=12345, progress=False).image
    mi_ref = None
    if mi is not None:
        mi_ref = mcs.mitsuba.render_reference(scene, ref_spp, seed=12345,
                                              integrator="direct").image
    theirs = {v: k for k, v in MITSUBA_SAMPLERS.items()}
    rows = []
    for spp in spp_list:
        for sampler in SAMPLERS:
            ours = np.mean([mcs.stats.relmse(mcs.render(
                scene, spp, integrator="direct", sampler=sampler, seed=k, progress=False).image,
                ours_ref) for k in range(seeds)])
            other = None
            if mi_ref is not None and sampler in theirs:
                other = float(np.mean([mcs.stats.relmse(mcs.mitsuba.render_reference(
                    scene, spp, seed=k, integrator="direct", sampler=theirs[sampler]).image,
                    mi_ref) for k in range(seeds)]))
            rows.append((spp, sampler, float(ours), other))
    return rows


def suite_samplers(n: int, repeat: int, mi) -> list[Timing]:
    """Render time per sample with each sampler (demo scene and a triangle
    mesh under the sky, 256 x 96, 64 spp, direct and path), beside Mitsuba
    3 (llvm_ad_rgb) with each of its samplers in the same run, and a table of
    the relMSE each reaches at equal spp beside Mitsuba's samplers
    (:func:`sampler_relmse`)."""
    from ..demo import demo_scene
    from ..scene import icosphere

    mesh = demo_scene(256, 96)
    v, f = icosphere(3)
    for key in [k for k in mesh if k.startswith("sphere_n")][:2]:
        sphere = mesh.pop(key)
        mesh[key.replace("sphere", "mesh")] = {
            "type": "mesh", "vertices": v * 0.5 + sphere["center"], "faces": f,
            "bsdf": sphere["bsdf"]}
    out = []
    for name, d in (("demo", demo_scene(256, 96)), ("demo with meshes", mesh)):
        scene = mcs.Scene.from_mitsuba(d)
        h, w = scene.shape
        for integrator in ("direct", "path"):
            runs = [(f"mcsample {s}", lambda s=s: mcs.render(
                scene, 64, integrator=integrator, sampler=s, progress=False)) for s in SAMPLERS]
            if mi is not None:
                # Mitsuba's samplers, the plain mi.render (its JIT warmed up
                # by measure_side_by_side's warm-up run).
                mi_int = mi.load_dict({"type": integrator})
                for kind in MITSUBA_SAMPLERS:
                    md = scene.to_mitsuba(spp=64)
                    md["sensor"]["sampler"]["type"] = kind
                    mi_scene = mi.load_dict(md)
                    runs.append((f"Mitsuba {kind}", lambda m=mi_scene: np.asarray(
                        mi.render(m, integrator=mi_int, spp=64))))
            seconds = measure_side_by_side([f for _, f in runs], min(repeat, 3), 1)
            out += [Timing(f"render {name}, {integrator}", impl, "float32", w * h * 64, t)
                    for (impl, _), t in zip(runs, seconds)]
    rows = sampler_relmse(mi)
    print("relMSE at equal spp, demo scene (direct, MIS), mean of 4 seeds, each renderer "
          "against its own 4096-spp render:")
    print(f"{'spp':>5s} {'mcsample':12s} {'relMSE':>9s}   {'Mitsuba':12s} {'relMSE':>9s}")
    theirs = {v: k for k, v in MITSUBA_SAMPLERS.items()}
    for spp, sampler, ours, other in rows:
        print(f"{spp:5d} {sampler:12s} {ours:9.5f}   {theirs.get(sampler, '-'):12s} "
              + (f"{other:9.5f}" if other is not None else f"{'-':>9s}"))
    return out


def difficult_room(width: int = 96, height: int = 72, max_depth: int = 8) -> dict:
    """Seed 003's difficult case: a closed room (the cube [-1, 1]³ seen from
    inside, diffuse walls) lit only by a small area light 0.2 under the
    ceiling that faces it, so that everything the camera sees is lit by
    the patch of ceiling above the light: paths of three segments or more,
    which next-event estimation from the walls finds only through that
    patch."""
    t = np.radians(-90.0)
    turn = np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])
    light = np.eye(4)
    light[:3, :3] = turn @ np.diag([0.15, 0.1, 1.0])
    light[:3, 3] = [0.1, 0.8, -0.2]
    return {"type": "scene",
            "sensor": {"type": "perspective", "fov": 70.0,
                       "to_world": mcs.look_at([0.0, -0.2, 0.95], [0.0, 0.1, -1.0], [0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": width, "height": height,
                                "rfilter": {"type": "box"}}},
            "integrator": {"type": "path", "max_depth": max_depth},
            "room": {"type": "cube", "flip_normals": True,
                     "bsdf": {"type": "diffuse", "reflectance": [0.7, 0.6, 0.5]}},
            "light": {"type": "rectangle", "to_world": light,
                      "emitter": {"type": "area", "radiance": 20.0},
                      "bsdf": {"type": "diffuse", "reflectance": 0.3}}}


def suite_bidirectional(n: int, repeat: int, mi, target: float = 0.05, spp: int = 16,
                        ref_spp: int = 256) -> list[Timing]:
    """Time to relMSE ``target`` on :func:`difficult_room` by path tracing,
    bidirectional path tracing and light tracing, and by Mitsuba's path
    tracer: relMSE ≈ C / spp (C measured at ``spp`` against a ``ref_spp``
    bidirectional reference, less the reference's own share measured
    between two of them), the time (C / target) spp at the measured
    seconds per spp."""
    scene = mcs.Scene.from_mitsuba(difficult_room())
    ours = {f"mcsample {i}": {"integrator": i} for i in ("path", "bdpt", "ptracer")}
    return _time_to_relmse(scene, ours, ours["mcsample bdpt"],
                           ("path", {"type": "path", "max_depth": 8}), (mi, repeat),
                           (target, "room"), (spp, ref_spp))


#: The mesh benchmarks' bumpy spheres: (rows, cols) of bumpy_sphere, and
#: their triangles.
MESHES = {"2e5": (251, 400), "1e6": (502, 1000)}


def bumpy_scene(rows: int, cols: int, size: int = 256, mesh: dict | None = None) -> dict:
    """The mesh benchmark: a Phong bumpy sphere (:func:`~mcsample.scene.bumpy_sphere`
    of ``rows`` × ``cols``, radius 0.7) on a diffuse ground, lit by the
    packaged sky and a small sphere area light, seen at ``size`` ×
    ``size`` through a box filter. ``mesh`` replaces the mesh's shape
    entry (a ``ply`` file of the same mesh)."""
    from ..scene import bumpy_sphere

    if mesh is None:
        v, f = bumpy_sphere(rows, cols)
        mesh = {"type": "mesh", "vertices": v * 0.7 + [0, 0.75, 0], "faces": f}
    sensor = {"type": "perspective", "fov": 35,
              "to_world": mcs.look_at([0, 1.2, 4.5], [0, 0.7, 0], [0, 1, 0]),
              "film": {"type": "hdrfilm", "width": size, "height": size,
                       "rfilter": {"type": "box"}}}
    floor = _render_scenes()["sphere on plane"]["floor"]
    return {"type": "scene", "sensor": sensor, "sky": mcs.EnvMap(), "floor": floor,
            "mesh": {**mesh, "bsdf": {"type": "mcsample_phong",
                                      "diffuse_reflectance": [0.3, 0.2, 0.1],
                                      "specular_reflectance": [0.6, 0.6, 0.6],
                                      "exponent": 30.0}},
            "lamp": {"type": "sphere", "center": [1.5, 2.5, 1.0], "radius": 0.3,
                     "emitter": {"type": "area", "radiance": [30.0, 28.0, 25.0]}}}


def _peak_rss(code: str) -> float:
    """Peak resident memory (MiB) of a fresh Python process running
    ``code``: its VmHWM (Linux; ``ru_maxrss`` would not do, as a child
    keeps its parent's high-water mark across fork and exec)."""
    import subprocess
    import sys

    script = code + ("\nprint(next(line.split()[1] for line in open('/proc/self/status')"
                     " if line.startswith('VmHWM')))")
    out = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True,
                         text=True).stdout
    return int(out.split()[-1]) / 1024


def _mitsuba_ply(mi, scene: "mcs.Scene", ply: str, spp: int) -> dict:
    """``scene.to_mitsuba()`` with its largest mesh read by Mitsuba's own
    ``ply`` plugin from ``ply`` (same BSDF and normals)."""
    d = scene.to_mitsuba(spp=spp)
    key = max((k for k, v in d.items() if isinstance(v, mi.Mesh)),
              key=lambda k: d[k].face_count())
    d[key] = {"type": "ply", "filename": ply, "bsdf": d[key].bsdf(),
              "face_normals": not d[key].has_vertex_normals()}
    return d


def suite_meshes(n: int, repeat: int, mi, spp: int = 64) -> list[Timing]:
    """The bumpy-sphere mesh scenes (:func:`bumpy_scene`, 2·10^5 and 10^6
    triangles): samples per second at 256 × 256, 64 spp, direct and path
    (max_depth 5), side by side with Mitsuba 3; the scene's build (BVH and
    all) from numpy arrays and from a PLY file (the "samples" column
    counting triangles), side by side with Mitsuba's ``load_dict`` (of
    ``to_mitsuba()``'s dict, and of its ``ply`` plugin); and the peak
    memory of a fresh process that loads the PLY scene and renders it once
    (printed; direct illumination). mcsample's rows name the ray tracer that ran."""
    import os
    import tempfile

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, (rows, cols) in MESHES.items():
            d = bumpy_scene(rows, cols)
            triangles = len(d["mesh"]["faces"])
            ply = os.path.join(tmp, f"bumpy-{label}.ply")
            mcs.io.write_ply(ply, d["mesh"]["vertices"], d["mesh"]["faces"])
            from_ply = bumpy_scene(rows, cols, mesh={"type": "ply", "filename": ply})
            scene = mcs.Scene.from_mitsuba(d)
            ours = f"mcsample ({scene.ray_tracer})"
            builds = {"arrays": [(ours, lambda: mcs.Scene.from_mitsuba(d).compiled)],
                      "ply": [(ours, lambda: mcs.Scene.from_mitsuba(from_ply).compiled)]}
            if mi is not None:
                ply_dict = _mitsuba_ply(mi, scene, ply, spp)
                # Mitsuba's meshes made from the arrays and its scene built
                # (mcsample's parse of the dict, done once, not timed).
                builds["arrays"].append(("mitsuba llvm_ad_rgb", lambda: mi.load_dict(
                    scene.to_mitsuba(spp=spp))))
                builds["ply"].append(("mitsuba llvm_ad_rgb", lambda: mi.load_dict(ply_dict)))
            for source, runs in builds.items():
                seconds = measure_side_by_side([r[1] for r in runs], min(repeat, 5), 1)
                out += [Timing(f"build {label}-triangle scene from {source}", impl, "float32",
                               triangles, t) for (impl, _), t in zip(runs, seconds)]
            mi_scene = None if mi is None else mi.load_dict(scene.to_mitsuba(spp=spp))
            h, w = scene.shape
            for integrator, depth in (("direct", {}), ("path", {"max_depth": 5})):
                runs = [(ours, lambda i=integrator, k=depth: mcs.render(
                    scene, spp, integrator=i, progress=False, **k))]
                if mi_scene is not None:
                    mi_int = mi.load_dict({"type": integrator, **depth})
                    runs.append(("mitsuba llvm_ad_rgb", lambda m=mi_int: np.asarray(
                        mi.render(mi_scene, integrator=m, spp=spp))))
                seconds = measure_side_by_side([r[1] for r in runs], min(repeat, 3), 2)
                out += [Timing(f"render {label}-triangle mesh, {integrator}", impl, "float32",
                               w * h * spp, t) for (impl, _), t in zip(runs, seconds)]
            load = ("import mcsample as mcs\nfrom mcsample.bench.renders import bumpy_scene\n"
                    f"scene = mcs.Scene.from_mitsuba(bumpy_scene({rows}, {cols}, "
                    f"mesh={{'type': 'ply', 'filename': {ply!r}}}))\n")
            rss = {ours: _peak_rss(load + f"mcs.render(scene, {spp}, progress=False)")}
            if mi is not None:
                # The scene's other parts from a stand-in of 6 triangles,
                # the mesh read by Mitsuba's ply plugin.
                rss["mitsuba llvm_ad_rgb"] = _peak_rss(
                    "import mcsample as mcs\nfrom mcsample.bench.renders import bumpy_scene\n"
                    "scene = mcs.Scene.from_mitsuba(bumpy_scene(3, 3))\n"
                    "import numpy as np\nimport mitsuba as mi\n"
                    f"mi.set_variant({mi.variant()!r})\n"
                    "from mcsample.bench.renders import _mitsuba_ply\n"
                    f"m = mi.load_dict(_mitsuba_ply(mi, scene, {ply!r}, {spp}))\n"
                    "direct = mi.load_dict({'type': 'direct'})\n"
                    f"np.asarray(mi.render(m, integrator=direct, spp={spp}))")
            print(f"peak RSS, {label}-triangle scene from PLY, one {spp}-spp render: "
                  + ", ".join(f"{k} {v:.0f} MiB" for k, v in rss.items()))
    return out
