"""mcsample's Phong against its independent Dr.Jit twin, registered in
Mitsuba 3 as "mcsample_phong": the plugin's samples against mcs.Phong.pdf
(chi-square), its eval against mcs.Phong.eval x cos, and the scalar variant
(in a subprocess, so the session keeps its variant)."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import mcsample as mcs
from mcsample import mitsuba as mcs_mitsuba
from mcsample import stats

pytestmark = pytest.mark.mitsuba

KD, KS = [0.2, 0.3, 0.1], [0.7, 0.5, 0.6]


def _plugin(mi, n):
    name = mcs_mitsuba.register_phong()
    assert name == "mcsample_phong"
    return mi.load_dict({"type": name,
                         "diffuse_reflectance": {"type": "rgb", "value": KD},
                         "specular_reflectance": {"type": "rgb", "value": KS},
                         "exponent": n})


def _rows(mi, v):
    a = np.array(v, dtype=np.float64)
    return a.T if a.ndim == 2 and a.shape[0] == 3 and a.shape[1] != 3 else a


def _sample(mi, bsdf, wi, u):
    import drjit as dr
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(*[float(c) for c in wi])
    u = u.astype(np.float32)
    bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(u[:, 2]),
                             mi.Point2f(u[:, 0], u[:, 1]))
    return _rows(mi, bs.wo), np.array(bs.pdf, dtype=np.float64), _rows(mi, weight)


def _llvm(mi):
    if mi.variant().startswith("scalar"):
        pytest.skip("needs the llvm variant for 10^6 vectorised samples; the scalar variant "
                    "is checked by test_plugin_in_the_scalar_variant")


@pytest.mark.parametrize("n,angle,zoom,ires", [(1.0, 0.0, 1.0, 4), (30.0, 60.0, 2.0, 8),
                                               (300.0, 85.0, 3.0, 16)])
def test_plugin_samples_follow_mcsample_pdf(mi, n, angle, zoom, ires):
    _llvm(mi)
    bsdf, phong = _plugin(mi, n), mcs.Phong(KD, KS, n)
    t = np.radians(angle)
    wi = np.array([np.sin(t), 0.0, np.cos(t)])
    frame = mcs.Frame([-wi[0], -wi[1], wi[2]])
    result = stats.chi2_test(lambda u: frame.to_local(_sample(mi, bsdf, wi, u)[0]),
                             lambda d: phong.pdf(wi, frame.to_world(d)),
                             stats.SphericalDomain(zoom), sample_dim=3, ires=ires, seed=9,
                             test_count=3)
    assert result.passed, result.message


def test_plugin_agrees_with_mcsample_on_the_same_u(mi):
    _llvm(mi)
    bsdf, phong = _plugin(mi, 20.0), mcs.Phong(KD, KS, 20.0)
    wi = np.array([np.sin(0.6), 0.0, np.cos(0.6)])
    u = mcs.uniform(100_000, 3, seed=1, dtype=np.float32).astype(np.float64)
    wo, pdf, weight = _sample(mi, bsdf, wi, u)
    ours = phong.sample(wi, u)
    # Same sampling: the same directions from the same u (float32 precision;
    # u[:, 2] within round-off of the selection threshold may differ).
    same = np.all(np.abs(wo - ours.wo) < 1e-4, axis=1)
    assert same.mean() > 0.9999
    assert np.allclose(pdf[same], ours.pdf[same], rtol=1e-4, atol=1e-6)
    assert np.allclose(weight[same], ours.weight[same], rtol=1e-4, atol=1e-6)


def test_plugin_eval_is_mcsample_eval_times_cosine(mi):
    import drjit as dr
    bsdf, phong = _plugin(mi, 50.0), mcs.Phong(KD, KS, 50.0)
    m = 64 if mi.variant().startswith("scalar") else 20_000
    wi = mcs.warp.square_to_uniform_hemisphere(mcs.uniform(m, 2, seed=2))
    wo = mcs.warp.square_to_uniform_sphere(mcs.uniform(m, 2, seed=3))
    # Put a third of the wo near the mirror direction, where the lobe lives.
    wo[::3] = phong.sample(wi[::3], mcs.uniform(len(wo[::3]), 3, seed=4)).wo
    expected = phong.eval(wi, wo) * np.maximum(wo[:, 2], 0)[:, None]
    if mi.variant().startswith("scalar"):
        got = []
        for a, b in zip(wi, wo):
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wi = mi.Vector3f(*a)
            got.append(np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*b))))
        got = np.array(got, dtype=np.float64)
    else:
        si = dr.zeros(mi.SurfaceInteraction3f, m)
        si.wi = mi.Vector3f(*(wi[:, k].astype(np.float32) for k in range(3)))
        got = _rows(mi, bsdf.eval(mi.BSDFContext(), si,
                                  mi.Vector3f(*(wo[:, k].astype(np.float32) for k in range(3)))))
    assert np.allclose(got, expected, rtol=2e-3, atol=1e-5), np.abs(got - expected).max()


def test_plugin_in_the_scalar_variant():
    if not mcs_mitsuba.available():
        pytest.skip("Mitsuba 3 is not installed")
    code = textwrap.dedent("""
        import numpy as np, drjit as dr, mcsample as mcs
        from mcsample import mitsuba as mm
        mi = mm.load("scalar_rgb")
        bsdf = mi.load_dict({"type": mm.register_phong(), "diffuse_reflectance": 0.25,
                             "specular_reflectance": [0.5, 0.6, 0.7], "exponent": 15.0})
        phong = mcs.Phong(0.25, [0.5, 0.6, 0.7], 15.0)
        wi = np.array([0.3, 0.0, np.sqrt(1 - 0.09)])
        si = dr.zeros(mi.SurfaceInteraction3f); si.wi = mi.Vector3f(*wi)
        u = mcs.uniform(300, 3, seed=5, dtype=np.float32).astype(np.float64)
        ours = phong.sample(wi, u)
        for k in range(len(u)):
            bs, w = bsdf.sample(mi.BSDFContext(), si, float(u[k, 2]), mi.Point2f(u[k, 0], u[k, 1]))
            assert np.allclose(np.array(bs.wo), ours.wo[k], atol=1e-4), (k, bs.wo, ours.wo[k])
            assert abs(bs.pdf - ours.pdf[k]) <= 1e-4 * max(1.0, ours.pdf[k])
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0 and "ok" in out.stdout, out.stderr[-2000:]


def test_register_phong_refuses_bad_materials(mi):
    name = mcs_mitsuba.register_phong()
    with pytest.raises(Exception, match="must be in"):
        mi.load_dict({"type": name, "diffuse_reflectance": 0.7, "specular_reflectance": 0.6})
