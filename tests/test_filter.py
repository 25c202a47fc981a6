"""The film's reconstruction filters (Mitsuba's ``box`` and ``gaussian``):
renders of a straight shadow edge against the exact filtered coverage, on
the film's edges (where the filter is cut to the film, or reaches over its
border with ``sample_border``), and renders against Mitsuba's."""

import numpy as np
import pytest

import mcsample as mcs
from mcsample import stats
from scenes import skip_scalar

#: Mitsuba 3.9's Gaussian on the CPU, a polynomial in x²/σ² (minimax fit to
#: exp(−y/2) on [0, 16]) shifted to 0 at the radius 4σ; written out here so
#: the oracle does not use mcsample's copy (and checked against Mitsuba's
#: own ``eval`` below).
GAUSSIAN = np.array([9.992604880e-1, -4.977025247e-1, 1.222248550e-1, -1.932406282e-2,
                     2.136713061e-3, -1.679873860e-4, 9.202145248e-6, -3.329417433e-7,
                     7.128382794e-9, -6.821193280e-11])


def gaussian(x, stddev):
    y = np.asarray(x, dtype=np.float64) ** 2 / stddev**2
    p = np.polynomial.polynomial.polyval
    return np.where(np.abs(x) < 4 * stddev, np.maximum(p(y, GAUSSIAN) - p(16.0, GAUSSIAN), 0), 0)


def integral(f, lo, hi, n=20_000):
    """∫_lo^hi f by Simpson's rule (f is smooth on the interval)."""
    if hi <= lo:
        return 0.0
    x = np.linspace(lo, hi, 2 * n + 1)
    w = np.ones_like(x)
    w[1:-1:2], w[2:-1:2] = 4, 2
    return float((w * f(x)).sum() * (hi - lo) / (6 * n))


WIDTH = 16


def edge_scene(rfilter, sample_border=False):
    """A white constant sky seen through a pinhole (fov 90 along x, 16 x 2
    pixels) with two black rectangles at z = 5: one hides film columns
    x < 0.7 (pixels from the left edge), the other x > 15.4. Columns map
    linearly to world x on the plane z = 5 (x_world = 5 (1 − 2 x / 16)),
    so each pixel's expected value is the filtered fraction of sky,
    1 − ∫ f(t) [c + t inside a rectangle] dt / ∫ f over the sampled film."""
    x0, x1 = (5 * (1 - 2 * e / WIDTH) for e in (0.7, 15.4))
    black = {"type": "diffuse", "reflectance": 0.0}

    def wall(lo, hi):
        return {"type": "rectangle", "bsdf": black,
                "to_world": np.array([[(hi - lo) / 2, 0, 0, (hi + lo) / 2], [0, 100, 0, 0],
                                      [0, 0, 1, 5], [0, 0, 0, 1.0]])}

    return mcs.Scene.from_mitsuba({
        "type": "scene", "sky": {"type": "constant", "radiance": 1.0},
        "left": wall(x0, x0 + 200), "right": wall(x1 - 200, x1),
        "sensor": {"type": "perspective", "fov": 90, "fov_axis": "x",
                   "film": {"type": "hdrfilm", "width": WIDTH, "height": 2,
                            "rfilter": rfilter, "sample_border": sample_border}}})


def expected_row(f, radius, border):
    """Each column's filtered sky fraction: the film (grown by ``border``)
    cuts the filter's support [−radius, radius] around the pixel centre."""
    out = []
    for i in range(WIDTH):
        c = i + 0.5
        lo, hi = max(-radius, -border - c), min(radius, WIDTH + border - c)
        hidden = integral(f, lo, min(hi, 0.7 - c)) + integral(f, max(lo, 15.4 - c), hi)
        out.append(1 - hidden / integral(f, lo, hi))
    return np.array(out)


CASES = [
    ({"type": "box"}, False, lambda x: np.ones_like(x), 0.5, 0),
    ({"type": "gaussian"}, False, lambda x: gaussian(x, 0.5), 2.0, 0),
    ({"type": "gaussian"}, True, lambda x: gaussian(x, 0.5), 2.0, 2),
    ({"type": "gaussian", "stddev": 0.3}, False, lambda x: gaussian(x, 0.3), 1.2, 0),
    ({"type": "gaussian", "stddev": 1.0}, True, lambda x: gaussian(x, 1.0), 4.0, 4),
]


@pytest.mark.parametrize("rfilter, border, f, radius, pixels", CASES,
                         ids=["box", "gaussian", "gaussian-border", "gaussian-0.3",
                              "gaussian-1.0-border"])
def test_edge_matches_the_filtered_coverage(rfilter, border, f, radius, pixels):
    """Per-pixel z-test of the render (16384 spp) against the exact filtered
    coverage. The columns next to the film's edges see the filter cut to
    the film (or reaching the border); a filter not cut there moves the
    first column by 0.065 (17 standard errors)."""
    r = mcs.render(edge_scene(rfilter, border), 16384, integrator="path", max_depth=1, seed=5)
    expected = expected_row(f, radius, pixels)
    sd = np.sqrt(r.luminance_variance)
    noisy = sd > 1e-7
    z = (r.luminance - expected)[noisy] / sd[noisy]
    assert np.all(np.abs(z) < 5), (r.luminance[0], expected, z)
    assert np.allclose(r.luminance[~noisy], np.broadcast_to(expected, r.luminance.shape)[~noisy],
                       atol=1e-5)
    # The oracle has power: every other case's values differ somewhere by
    # more than 8 standard errors of this render.
    for other in CASES:
        if other[:2] != (rfilter, border):
            gap = np.abs(expected_row(*other[2:]) - expected) / np.maximum(sd[0], 1e-4)
            assert gap.max() > 8, (other[:2], gap.max())


def test_filter_defaults_and_bad_values():
    d = {"type": "scene", "sky": {"type": "constant"},
         "sensor": {"type": "perspective", "fov": 40,
                    "film": {"type": "hdrfilm", "width": 8, "height": 4}}}
    cam = mcs.Scene.from_mitsuba(d).camera
    assert (cam.rfilter, cam.stddev, cam.sample_border) == ("gaussian", 0.5, False)
    d["sensor"]["film"]["rfilter"] = {"type": "gaussian", "stddev": 65}
    with pytest.raises(ValueError, match=r"sensor.film.rfilter.stddev = 65.0: must lie in"):
        mcs.Scene.from_mitsuba(d)
    b = mcs.scene.SceneBuilder()
    with pytest.raises(ValueError, match="rfilter"):
        b.set_filter("tent", 0.5, False)
    with pytest.raises(ValueError, match="stddev"):
        b.set_filter("gaussian", float("nan"), False)


@pytest.mark.mitsuba
def test_gaussian_is_mitsubas(mi):
    f = mi.load_dict({"type": "gaussian", "stddev": 0.7})
    x = np.linspace(-3, 3, 601)
    theirs = np.array([f.eval(mi.Float(v))[0] if hasattr(mi.Float(v), "__getitem__")
                       else f.eval(v) for v in x])
    assert np.allclose(gaussian(x, 0.7), theirs, atol=2e-5)


@pytest.mark.mitsuba
@pytest.mark.parametrize("border", [False, True])
def test_render_agrees_with_mitsubas_gaussian(mi, border):
    """A sphere on a plane under an area light and the sky, seen with
    Mitsuba's default filter: mcsample's render is z-test-equal to
    Mitsuba's (16 independent renders: its pixels share samples), with the
    film's edges in the image. Power: the same render with a box filter
    (an image less blurred) is rejected."""
    from scenes import sphere_on_plane

    d = sphere_on_plane()
    d["sensor"]["film"].update(rfilter={"type": "gaussian"}, sample_border=border)
    d["lamp"] = {"type": "sphere", "center": [0.6, 1.6, 0.4], "radius": 0.15,
                 "emitter": {"type": "area", "radiance": 40.0}}
    skip_scalar(mi)
    s = mcs.Scene.from_mitsuba(d)
    ref = mcs.mitsuba.render_reference(s, 256, seed=1, integrator="direct")
    assert ref.runs is not None and ref.runs.shape == (16, 36, 48)
    ours = mcs.render(s, 256, integrator="direct", seed=2)
    t = stats.render_ztest(ours, ref)
    assert t.passed, t.message
    d["sensor"]["film"]["rfilter"] = {"type": "box"}
    boxed = mcs.render(mcs.Scene.from_mitsuba(d), 256, integrator="direct", seed=2)
    assert not stats.render_ztest(boxed, ref).passed
