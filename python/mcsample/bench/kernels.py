"""Kernel suites: random numbers, warps, discrete tables, Phong, envmap
sampling and the QMC engines, beside numpy, scipy and Mitsuba."""

from __future__ import annotations

from typing import Callable

import numpy as np

import mcsample as mcs

from .timing import Timing, measure, measure_alternating, measure_side_by_side


def _numpy_concentric_disk(u: np.ndarray) -> np.ndarray:
    """Shirley and Chiu's concentric disk, vectorised with numpy: (N, 2)."""
    a, b = 2 * u[:, 0] - 1, 2 * u[:, 1] - 1
    horizontal = np.abs(a) >= np.abs(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(horizontal, a, b)
        phi = np.where(horizontal, (np.pi / 4) * (b / a), np.pi / 2 - (np.pi / 4) * (a / b))
    phi = np.where(r == 0, 0, phi)
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def _numpy_cosine_hemisphere(u: np.ndarray) -> np.ndarray:
    """Malley's method on the concentric disk, vectorised with numpy."""
    p = _numpy_concentric_disk(u)
    z = np.sqrt(np.maximum(0, 1 - p[:, 0] ** 2 - p[:, 1] ** 2))
    return np.concatenate([p, z[:, None]], axis=1)


def _numpy_uniform_cone(u: np.ndarray, cos_cutoff: float) -> np.ndarray:
    """The uniform cone on the concentric disk (as mi.warp), with numpy; the
    hemisphere is the cone of cos_cutoff = 0."""
    p = _numpy_concentric_disk(u)
    r2 = p[:, 0] ** 2 + p[:, 1] ** 2
    one_minus_c = 1 - cos_cutoff
    scale = np.sqrt(np.maximum(0, one_minus_c * (2 - one_minus_c * r2)))
    return np.concatenate([p * scale[:, None], (1 - one_minus_c * r2)[:, None]], axis=1)


def _numpy_uniform_hemisphere(u: np.ndarray) -> np.ndarray:
    return _numpy_uniform_cone(u, 0.0)


def _numpy_cosine_power_hemisphere(u: np.ndarray, exponent: float) -> np.ndarray:
    cos_t = u[:, 1] ** (1 / (exponent + 1))
    sin_t = np.sqrt(np.maximum(0, 1 - cos_t ** 2))
    phi = 2 * np.pi * u[:, 0]
    return np.stack([np.cos(phi) * sin_t, np.sin(phi) * sin_t, cos_t], axis=1)


def _numpy_uniform_sphere(u: np.ndarray) -> np.ndarray:
    z = 1 - 2 * u[:, 1]
    r = np.sqrt(np.maximum(0, 1 - z * z))
    phi = 2 * np.pi * u[:, 0]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def suite_rng(n: int, repeat: int, mi) -> list[Timing]:
    out = [Timing("uniform (n, 2)", "mcsample", "float64", n,
                  measure(lambda: mcs.uniform(n // 2, 2), repeat)),
           Timing("uniform (n, 2)", "mcsample", "float32", n,
                  measure(lambda: mcs.uniform(n // 2, 2, dtype=np.float32), repeat))]
    gen = np.random.default_rng(0)
    out.append(Timing("uniform (n, 2)", "numpy PCG64", "float64", n,
                      measure(lambda: gen.random((n // 2, 2)), repeat)))
    out.append(Timing("uniform (n, 2)", "numpy PCG64", "float32", n,
                      measure(lambda: gen.random((n // 2, 2), dtype=np.float32), repeat)))
    if mi is not None:
        import drjit as dr

        def drjit_pcg32():
            rng = mi.PCG32(size=n)
            x = rng.next_float32()
            dr.eval(x)
            dr.sync_thread()

        out.append(Timing("uniform (n, 2)", "Dr.Jit PCG32 (llvm)", "float32", n,
                          measure(drjit_pcg32, repeat)))
    return out


def _numpy_uniform_disk(u: np.ndarray) -> np.ndarray:
    r, phi = np.sqrt(u[:, 1]), 2 * np.pi * u[:, 0]
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def _numpy_uniform_triangle(u: np.ndarray) -> np.ndarray:
    t = np.sqrt(1 - u[:, 0])
    return np.stack([1 - t, t * u[:, 1]], axis=1)


def _numpy_std_normal(u: np.ndarray) -> np.ndarray:
    r = np.sqrt(-2.0 * np.log1p(-u[:, 0]))
    phi = 2.0 * np.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def suite_warps(n: int, repeat: int, mi) -> list[Timing]:
    """Every forward warp, float64 and float32, beside numpy (where a
    numpy version is written here) and Mitsuba 3 llvm (float32)."""
    u64 = mcs.uniform(n, 2, seed=1)
    u32 = u64.astype(np.float32)
    w = mcs.warp
    cases = [
        ("square_to_uniform_disk", w.square_to_uniform_disk, _numpy_uniform_disk, ()),
        ("square_to_uniform_disk_concentric", w.square_to_uniform_disk_concentric,
         _numpy_concentric_disk, ()),
        ("square_to_uniform_sphere", w.square_to_uniform_sphere, _numpy_uniform_sphere, ()),
        ("square_to_uniform_hemisphere", w.square_to_uniform_hemisphere,
         _numpy_uniform_hemisphere, ()),
        ("square_to_cosine_hemisphere", w.square_to_cosine_hemisphere,
         _numpy_cosine_hemisphere, ()),
        ("square_to_uniform_cone", w.square_to_uniform_cone, _numpy_uniform_cone, (0.3,)),
        ("square_to_uniform_triangle", w.square_to_uniform_triangle,
         _numpy_uniform_triangle, ()),
        ("square_to_cosine_power_hemisphere", w.square_to_cosine_power_hemisphere,
         _numpy_cosine_power_hemisphere, (10.0,)),
        ("square_to_std_normal", w.square_to_std_normal, _numpy_std_normal, ()),
        ("square_to_beckmann", w.square_to_beckmann, None, (0.3,)),
        ("square_to_von_mises_fisher", w.square_to_von_mises_fisher, None, (5.0,)),
    ]
    out = []
    for name, ours, numpy_impl, args in cases:
        # float32: the plain call, the call into a reused array (out=, as
        # Dr.Jit reuses its memory) and Mitsuba, timed in alternating
        # blocks, so that no two of them are compared across a change of
        # the machine's speed.
        pair: list[tuple[str, Callable[[], object]]] = []
        for dtype, u in (("float64", u64), ("float32", u32)):
            plain = (lambda u=u: ours(u, *args))
            buffer = np.empty_like(ours(u[:2], *args), shape=(n,) + ours(u[:1], *args).shape[1:])
            reused = (lambda u=u, buffer=buffer: ours(u, *args, out=buffer))
            if dtype == "float32":
                pair += [("mcsample", plain), ("mcsample out=", reused)]
            else:
                out.append(Timing(name, "mcsample", dtype, n, measure(plain, repeat)))
                out.append(Timing(name, "mcsample out=", dtype, n, measure(reused, repeat)))
            if numpy_impl is not None:
                out.append(Timing(name, "numpy", dtype, n,
                                  measure(lambda: numpy_impl(u, *args), repeat)))
        fn = getattr(mi.warp, name, None) if mi is not None else None
        if fn is not None and not name.endswith("power_hemisphere"):
            import drjit as dr

            p = mi.Point2f(u32[:, 0], u32[:, 1])

            def run():
                d = fn(p, *args)
                dr.eval(d)
                dr.sync_thread()

            pair.append(("Mitsuba 3 llvm", run))
        seconds = measure_alternating([f for _, f in pair], repeat)
        out += [Timing(name, impl, "float32", n, t) for (impl, _), t in zip(pair, seconds)]
    return out


def suite_distr(n: int, repeat: int, mi) -> list[Timing]:
    """Discrete tables of 10^6 weights: building (reported per entry) and
    sampling n indices, beside numpy, scipy and Mitsuba 3 llvm. The builds
    and the samplers of mcsample and Mitsuba are timed in alternating blocks
    (builds with builds, samplers with samplers), as the warps are."""
    size = 1_000_000
    weights = np.random.default_rng(0).random(size)
    u = mcs.uniform(n, 1, seed=2)[:, 0]
    d, a = mcs.Discrete1D(weights), mcs.AliasTable(weights)
    builds: list[tuple[str, str, Callable[[], object]]] = [
        ("mcsample Discrete1D", "float64", lambda: mcs.Discrete1D(weights)),
        ("mcsample AliasTable", "float64", lambda: mcs.AliasTable(weights)),
    ]
    # The plain calls, and the same into a reused array (out=).
    u32 = u.astype(np.float32)
    reused = np.empty(n, np.int64)
    samplers: list[tuple[str, str, Callable[[], object]]] = [
        ("mcsample Discrete1D", "float64", lambda: d.sample(u)),
        ("mcsample Discrete1D out=", "float64", lambda: d.sample(u, out=reused)),
        ("mcsample Discrete1D", "float32", lambda: d.sample(u32)),
        ("mcsample Discrete1D out=", "float32", lambda: d.sample(u32, out=reused)),
        ("mcsample AliasTable", "float64", lambda: a.sample(u)),
        ("mcsample AliasTable out=", "float64", lambda: a.sample(u, out=reused)),
    ]
    if mi is not None:
        import drjit as dr

        w32 = weights.astype(np.float32)
        def mi_build():
            # The constructor only records the running sums: evaluate them.
            built = mi.DiscreteDistribution(w32)
            dr.eval(built.cdf)
            dr.sync_thread()

        dist = mi.DiscreteDistribution(w32)
        uf = mi.Float(u32)

        def mi_sample():
            i = dist.sample(uf)
            dr.eval(i)
            dr.sync_thread()

        builds.append(("Mitsuba 3 llvm", "float32", mi_build))
        samplers.append(("Mitsuba 3 llvm", "float32", mi_sample))
    out = []
    for case, count, runs in (("build 10^6 (entries/s)", size, builds),
                              ("sample 10^6 table", n, samplers)):
        seconds = measure_alternating([f for _, _, f in runs], repeat)
        out += [Timing(case, impl, dtype, count, t)
                for (impl, dtype, _), t in zip(runs, seconds)]
    out += _distr_methods(n, repeat, mi)
    cdf = np.cumsum(weights)
    out.append(Timing("sample 10^6 table", "numpy searchsorted", "float64", n,
                      measure(lambda: np.searchsorted(cdf, u * cdf[-1]), repeat)))
    try:
        import warnings

        from scipy.stats.sampling import DiscreteAliasUrn

        # UNU.RAN warns about round-off for 10^6 entries; it still samples.
        warnings.filterwarnings("ignore", category=RuntimeWarning, module="mcsample.bench.kernels")

        out.append(Timing("build 10^6 (entries/s)", "scipy DiscreteAliasUrn", "float64", size,
                          measure(lambda: DiscreteAliasUrn(weights, random_state=1), 3, 1)))
        urn = DiscreteAliasUrn(weights, random_state=1)
        out.append(Timing("sample 10^6 table", "scipy DiscreteAliasUrn", "float64", n,
                          measure(lambda: urn.rvs(n), repeat)))
    except ImportError:
        pass
    return out


def _distr_methods(n: int, repeat: int, mi) -> list[Timing]:
    """The distributions' other batch methods on float32 u, the plain call,
    into reused arrays (out=) and Mitsuba's equivalent where it has one,
    alternating: ``sample_reuse`` of 1000 weights, a 128 x 256
    ``Discrete2D`` and ``PiecewiseConstant1D.sample`` over 1000 values
    (Mitsuba's ``ContinuousDistribution`` is piecewise linear, another
    density: not timed beside it)."""
    rng = np.random.default_rng(7)
    w1, w2 = rng.random(1000), rng.random((128, 256))
    u1 = mcs.uniform(n, 1, seed=8)[:, 0].astype(np.float32)
    u2 = mcs.uniform(n, 2, seed=9).astype(np.float32)
    d1, d2, p1 = mcs.Discrete1D(w1), mcs.Discrete2D(w2), mcs.PiecewiseConstant1D(w1)
    i1, i2 = np.empty(n, np.int64), np.empty((n, 2), np.int64)
    f1, f1b = np.empty(n, np.float32), np.empty(n, np.float32)
    cases: dict[str, list[tuple[str, Callable[[], object]]]] = {
        "Discrete1D.sample_reuse 1000": [
            ("mcsample", lambda: d1.sample_reuse(u1)),
            ("mcsample out=", lambda: d1.sample_reuse(u1, out=(i1, f1)))],
        "Discrete2D.sample 128x256": [
            ("mcsample", lambda: d2.sample(u2)),
            ("mcsample out=", lambda: d2.sample(u2, out=i2))],
        "PiecewiseConstant1D.sample 1000": [
            ("mcsample", lambda: p1.sample(u1)),
            ("mcsample out=", lambda: p1.sample(u1, out=(f1, f1b)))],
    }
    if mi is not None:
        import drjit as dr

        def run(f):
            def go():
                dr.eval(f())
                dr.sync_thread()
            return go

        uf, u2f = mi.Float(u1), mi.Point2f(u2[:, 0], u2[:, 1])
        m1 = mi.DiscreteDistribution(w1.astype(np.float32))
        m2 = mi.DiscreteDistribution2D(w2.astype(np.float32))
        cases["Discrete1D.sample_reuse 1000"].append(
            ("Mitsuba 3 llvm", run(lambda: m1.sample_reuse(uf))))
        cases["Discrete2D.sample 128x256"].append(
            ("Mitsuba 3 llvm", run(lambda: m2.sample(u2f))))
    out = []
    for case, runs in cases.items():
        seconds = measure_alternating([f for _, f in runs], repeat)
        out += [Timing(case, impl, "float32", n, t) for (impl, _), t in zip(runs, seconds)]
    return out


def _numpy_phong_sample(wi, u, kd, ks, n, pd):
    """Phong.sample vectorised with numpy (float64): mixture selection,
    cosine or cos^n lobe around the mirror direction, pdf and weight."""
    r = np.array([-wi[0], -wi[1], wi[2]])
    diffuse = u[:, 2] < pd
    d = _numpy_cosine_hemisphere(u[:, :2])
    phi = 2 * np.pi * u[:, 0]
    cos_t = u[:, 1] ** (1 / (n + 1))
    sin_t = np.sqrt(np.maximum(0, 1 - cos_t ** 2))
    local = np.stack([np.cos(phi) * sin_t, np.sin(phi) * sin_t, cos_t], 1)
    sign = np.copysign(1.0, r[2])
    a = -1 / (sign + r[2])
    b = r[0] * r[1] * a
    s_ax = np.array([1 + sign * r[0] ** 2 * a, sign * b, -sign * r[0]])
    t_ax = np.array([b, sign + r[1] ** 2 * a, -r[1]])
    lobe_dir = local[:, :1] * s_ax + local[:, 1:2] * t_ax + local[:, 2:] * r
    wo = np.where(diffuse[:, None], d, lobe_dir)
    cos_a = np.maximum(wo @ r, 0)
    lobe = cos_a ** n
    cos_o = np.maximum(wo[:, 2], 0)
    pdf = pd * cos_o / np.pi + (1 - pd) * (n + 1) / (2 * np.pi) * lobe
    f = kd / np.pi + ks * ((n + 2) / (2 * np.pi) * lobe)[:, None]
    f = np.where((cos_o > 0)[:, None], f, 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        weight = np.where((pdf > 0)[:, None], f * cos_o[:, None] / pdf[:, None], 0)
    return wo, pdf, weight


def suite_phong(n: int, repeat: int, mi) -> list[Timing]:
    """Phong.sample (10^7 directions for one wi, exponent 50) against numpy."""
    kd, ks, exponent = np.array([0.2, 0.3, 0.1]), np.array([0.7, 0.5, 0.6]), 50.0
    phong = mcs.Phong(kd, ks, exponent)
    wi = np.array([np.sin(0.5), 0.0, np.cos(0.5)])
    u64 = mcs.uniform(n, 3, seed=3)
    u32 = u64.astype(np.float32)
    pd = phong.diffuse_probability
    return [
        Timing("Phong.sample (exponent 50)", "mcsample", "float64", n,
               measure(lambda: phong.sample(wi, u64), repeat)),
        Timing("Phong.sample (exponent 50)", "mcsample", "float32", n,
               measure(lambda: phong.sample(wi, u32), repeat)),
        Timing("Phong.sample (exponent 50)", "numpy", "float64", n,
               measure(lambda: _numpy_phong_sample(wi, u64, kd, ks, exponent, pd), max(repeat // 2, 1), 1)),
    ]


def _numpy_envmap_sampler(image: np.ndarray):
    """Lat-long envmap sampling with numpy: luminance x sin(theta) per texel,
    marginal CDF over rows, conditional CDFs within rows, searchsorted."""
    h, w, _ = image.shape
    lum = image @ np.array([0.2126, 0.7152, 0.0722])
    weights = lum * np.sin(np.pi * (np.arange(h) + 0.5) / h)[:, None]
    rows = np.cumsum(weights, axis=1)
    marginal = np.cumsum(rows[:, -1])
    total = marginal[-1]

    def sample(u: np.ndarray):
        y = np.minimum(np.searchsorted(marginal, u[:, 1] * total, side="right"), h - 1)
        row = rows[y]
        x = np.minimum((row < (u[:, 0] * row[:, -1])[:, None]).sum(1), w - 1)
        v = (y + 0.5) / h
        uu = (x + 0.5) / w
        theta, phi = np.pi * v, 2 * np.pi * uu
        d = np.stack([np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)], 1)
        pdf = weights[y, x] / total * w * h / (2 * np.pi**2 * np.sin(theta))
        return d, pdf, image[y, x] / pdf[:, None]

    return sample


def suite_envmap(n: int, repeat: int, mi) -> list[Timing]:
    """The packaged sky resampled to 1024 x 512 (and 2048 x 1024 for the
    build): EnvMap build, sample and pdf beside Mitsuba 3's envmap emitter
    (llvm) and a numpy sampler (on 1/10 of the samples)."""
    sky = {res: mcs.EnvMap().convert("latlong", res).image for res in [1024, 2048]}
    image = sky[1024]
    out = []
    for res, img in sky.items():
        label = f"EnvMap build {res}x{res // 2} (texels/s)"
        out.append(Timing(label, "mcsample", "float32", img.shape[0] * img.shape[1],
                          measure(lambda img=img: mcs.EnvMap(img), repeat)))
        if mi is not None:
            bitmap = mi.Bitmap(img)
            out.append(Timing(label, "Mitsuba 3 llvm", "float32", img.shape[0] * img.shape[1],
                              measure(lambda bitmap=bitmap: mi.load_dict(
                                  {"type": "envmap", "bitmap": bitmap}), repeat)))
    env = mcs.EnvMap(image)
    u64 = mcs.uniform(n, 2, seed=5)
    u32 = u64.astype(np.float32)
    d64 = env.sample(u64).direction
    d32 = d64.astype(np.float32)
    # Into arrays reused from call to call (out=), as Dr.Jit reuses its
    # memory: no page faults on fresh results.
    reused = (np.empty_like(d32), np.empty(n, np.float32), np.empty_like(d32))
    # (case, implementation, dtype, function), timed side by side.
    cases = [
        ("EnvMap.sample 1024x512", "mcsample", "float64", lambda: env.sample(u64)),
        ("EnvMap.sample 1024x512", "mcsample", "float32", lambda: env.sample(u32)),
        ("EnvMap.sample 1024x512", "mcsample out=", "float32",
         lambda: env.sample(u32, out=reused)),
        ("EnvMap.pdf 1024x512", "mcsample", "float64", lambda: env.pdf(d64)),
        ("EnvMap.pdf 1024x512", "mcsample", "float32", lambda: env.pdf(d32)),
        ("EnvMap.pdf 1024x512", "mcsample out=", "float32",
         lambda: env.pdf(d32, out=reused[1])),
        ("EnvMap.eval 1024x512", "mcsample", "float32", lambda: env.eval(d32)),
        ("EnvMap.eval 1024x512", "mcsample out=", "float32",
         lambda: env.eval(d32, out=reused[2])),
    ]
    if mi is not None:
        import drjit as dr

        emitter = mi.load_dict({"type": "envmap", "bitmap": mi.Bitmap(image)})
        it = dr.zeros(mi.Interaction3f, n)
        uf = mi.Point2f(u32.T)

        def mi_sample():
            ds, w = emitter.sample_direction(it, uf)
            dr.eval(ds.d, ds.pdf, w)
            dr.sync_thread()

        ds = dr.zeros(mi.DirectionSample3f, n)
        ds.d = mi.Vector3f(d32.T)

        def mi_pdf():
            p = emitter.pdf_direction(it, ds)
            dr.eval(p)
            dr.sync_thread()

        cases += [("EnvMap.sample 1024x512", "Mitsuba 3 llvm", "float32", mi_sample),
                  ("EnvMap.pdf 1024x512", "Mitsuba 3 llvm", "float32", mi_pdf)]
    seconds = measure_side_by_side([c[3] for c in cases], repeat)
    out += [Timing(case, impl, dtype, n, t) for (case, impl, dtype, _), t in zip(cases, seconds)]
    numpy_sample = _numpy_envmap_sampler(image)
    m = max(n // 10, 1)
    out.append(Timing("EnvMap.sample 1024x512", "numpy", "float64", m,
                      measure(lambda: numpy_sample(u64[:m]), max(repeat // 2, 1), 1)))
    return out


def suite_qmc(n: int, repeat: int, mi) -> list[Timing]:
    """QMC engines drawing 2^20 points whatever ``n`` (the size the issue's
    figures are for; values counted: points × d), beside scipy.stats.qmc's
    engines of the same kind, from a reset engine each time."""
    from scipy.stats import qmc as scipy_qmc

    points = 2**20
    cases: list[tuple[str, list[tuple[str, Callable[[], object]]]]] = []
    for d in (2, 8):
        for ours, theirs, label in [(False, False, "plain"), (True, True, "scrambled"),
                                    ("lms", True, "lms")]:
            e, s = mcs.qmc.Sobol(d, scramble=ours, seed=1), scipy_qmc.Sobol(d, scramble=theirs, rng=1)
            cases.append((f"Sobol d={d} {label}",
                          [("mcsample", lambda e=e: e.reset().random(points)),
                           ("scipy", lambda s=s: s.reset().random(points))]))
    for scramble in (False, True):
        e, s = mcs.qmc.Halton(8, scramble=scramble, seed=1), scipy_qmc.Halton(8, scramble=scramble, rng=1)
        cases.append((f"Halton d=8 {'scrambled' if scramble else 'plain'}",
                      [("mcsample", lambda e=e: e.reset().random(points)),
                       ("scipy", lambda s=s: s.reset().random(points))]))
    e, s = mcs.qmc.LatinHypercube(8, seed=1), scipy_qmc.LatinHypercube(8, rng=1)
    cases.append(("LatinHypercube d=8", [("mcsample", lambda: e.random(points)),
                                         ("scipy", lambda: s.random(points))]))
    for engine in (mcs.qmc.Stratified(8, seed=1), mcs.qmc.MultiJitter(8, seed=1)):
        cases.append((f"{type(engine).__name__} d=8",
                      [("mcsample", lambda engine=engine: engine.random(points))]))
    out = []
    for case, runs in cases:
        d = int(case.split("d=")[1].split()[0])
        seconds = measure_side_by_side([f for _, f in runs], repeat=repeat, warmup=1)
        out += [Timing(case, impl, "float64", points * d, t) for (impl, _), t in zip(runs, seconds)]
    return out
