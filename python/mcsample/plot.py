"""Plots for notebooks: samples on their domain, chi-square histograms,
distributions, environment maps with their sampling density, Phong lobes,
convergence, tone-mapped HDR images and error maps.

matplotlib is imported when a function here is first called, so the rest of
mcsample does not need it (``pip install "mcsample[plot]"``). Every function
draws into ``ax`` / ``axes`` when given, and returns the Axes or Figure it
drew; none calls ``plt.show()``. Without ``ax``, a function that returns an
Axes draws into a new pyplot figure (which a notebook shows by itself); one
that returns a Figure makes it outside pyplot's state, so that a notebook
cell ending with it shows it once, as its value (in a script, save it with
``fig.savefig``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from .stats import (Chi2Result, Domain, DomainLike, SphericalDomain, luminance, make_domain,
                    relmse, render_ztest)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "chi2",
    "compare",
    "convergence",
    "distribution",
    "envmap",
    "error_map",
    "image",
    "phong_lobe",
    "samples",
    "strategies",
    "tonemap",
]


def _pyplot() -> Any:
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - matplotlib is a test dependency
        raise ImportError("mcsample.plot needs matplotlib: pip install 'mcsample[plot]'") from e
    return plt


def _figure(**kwargs: Any) -> Figure:
    """A new Figure not registered with pyplot (see the module doc)."""
    _pyplot()
    from matplotlib.figure import Figure

    return Figure(**kwargs)


def _axes(ax: Axes | None, **subplot_kw: Any) -> Axes:
    """``ax``, or the single Axes of a new figure."""
    if ax is not None:
        return ax
    _, ax = _pyplot().subplots(subplot_kw=subplot_kw or None)
    return ax


def _thin(count: int, max_points: int, seed: int = 0) -> np.ndarray | slice:
    """Indices of at most ``max_points`` of ``count`` points, drawn without
    replacement, in order."""
    if count <= max_points:
        return slice(None)
    return np.sort(np.random.default_rng(seed).choice(count, max_points, replace=False))


# --------------------------------------------------------------------------
# Images


def tonemap(image: Any, exposure: float = 0.0) -> np.ndarray:
    """A linear HDR image (H, W, 3) (or (H, W)) scaled by 2^exposure,
    clipped to [0, 1] and encoded with the sRGB transfer curve; float64 of
    the same shape, ready for ``imshow``. NaN shows as black."""
    x = np.nan_to_num(np.asarray(image, dtype=np.float64) * 2.0 ** exposure, nan=0.0)
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def image(img: Any, exposure: float = 0.0, ax: Axes | None = None,
          title: str | None = None) -> Axes:
    """An HDR image (H, W, 3) linear RGB, or a RenderResult, tone-mapped
    (:func:`tonemap`) and shown without axes."""
    ax = _axes(ax)
    ax.imshow(tonemap(getattr(img, "image", img), exposure), interpolation="nearest")
    ax.set_axis_off()
    if title:
        ax.set_title(title)
    return ax


def _z_scores(img: Any, reference: Any, variance: Any, reference_variance: Any) -> np.ndarray:
    """Per-pixel z-scores for :func:`error_map` (see there)."""
    renders = all(hasattr(x, "luminance_variance") for x in (img, reference))
    if renders and variance is None and reference_variance is None:
        return render_ztest(img, reference).z
    a = np.asarray(getattr(img, "luminance", img), dtype=np.float64)
    b = np.asarray(getattr(reference, "luminance", reference), dtype=np.float64)
    if variance is None:
        variance = getattr(img, "luminance_variance", None)
    if reference_variance is None:
        reference_variance = getattr(reference, "luminance_variance", None)
    if variance is None:
        raise ValueError("kind = 'z' needs variance= (the variance of the mean of img)")
    var = np.asarray(variance, dtype=np.float64)
    if reference_variance is not None:
        var = var + np.asarray(reference_variance, dtype=np.float64)
    if a.ndim != 2 or a.shape != b.shape or a.shape != var.shape:
        raise ValueError(f"kind = 'z' needs (H, W) images and variances of one shape, got "
                         f"{a.shape}, {b.shape}, {var.shape} (use .luminance and "
                         ".luminance_variance)")
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(var > 0, (a - b) / np.sqrt(var), 0.0)


def error_map(img: Any, reference: Any, kind: str = "relative", variance: Any = None,
              reference_variance: Any = None, eps: float = 1e-2, vmax: float | None = None,
              ax: Axes | None = None) -> Axes:
    """A per-pixel error map with its colour bar.

    - ``kind="relative"``: |L - L_ref| / (L_ref + eps) of the luminances
      (images (H, W, 3) or (H, W); RenderResults are accepted);
    - ``kind="absolute"``: |L - L_ref|;
    - ``kind="z"``: z = (a - b) / sqrt(var_a + var_b) on (H, W) arrays —
      e.g. ``result.luminance`` with ``variance=result.luminance_variance``
      — drawn from -5 to 5 (N(0, 1) if both are unbiased estimates of the
      same image). ``reference_variance`` may be None for an exact reference.
      Given two renders and no variances, the z-scores of
      :func:`mcsample.stats.render_ztest` (0 on noise-free pixels).
    """
    ax = _axes(ax)
    if kind == "z":
        limit = vmax or 5.0
        z = _z_scores(img, reference, variance, reference_variance)
        im = ax.imshow(z, cmap="RdBu_r", vmin=-limit, vmax=limit, interpolation="nearest")
        label = "z-score"
    elif kind in ("relative", "absolute"):
        a, b = (np.asarray(getattr(x, "image", x), dtype=np.float64) for x in (img, reference))
        a, b = (luminance(x) if x.ndim == 3 else x for x in (a, b))
        if a.shape != b.shape:
            raise ValueError(f"image shape {a.shape} differs from reference shape {b.shape}")
        err = np.abs(a - b)
        if kind == "relative":
            err = err / (np.abs(b) + eps)
        im = ax.imshow(err, cmap="magma", vmin=0, vmax=vmax or (1.0 if kind == "relative"
                                                                else None),
                       interpolation="nearest")
        label = "relative error" if kind == "relative" else "absolute error"
    else:
        raise ValueError(f"kind = {kind!r}: expected 'relative', 'absolute' or 'z'")
    ax.figure.colorbar(im, ax=ax, label=label, shrink=0.85)
    ax.set_axis_off()
    return ax


def compare(images: Mapping[str, Any], reference: Any, exposure: float = 0.0,
            kind: str = "relative", fig: Figure | None = None) -> Figure:
    """Images side by side (top row, tone-mapped, titled with their relMSE
    against ``reference``) above their error maps (bottom row, see
    :func:`error_map`; ``kind="z"`` needs RenderResults with variances).
    ``images`` maps a name to an image (H, W, 3) or a RenderResult."""
    ref = np.asarray(getattr(reference, "image", reference))
    if fig is None:
        h, w = ref.shape[:2]
        fig = _figure(figsize=(4.0 * len(images), 8.0 * h / w + 1.5), layout="constrained")
    axes = fig.subplots(2, len(images), squeeze=False)
    for col, (name, img) in enumerate(images.items()):
        err = relmse(getattr(img, "image", img), ref)
        image(img, exposure, ax=axes[0, col], title=f"{name}\nrelMSE {err:.3g}")
        error_map(img, reference, kind=kind, ax=axes[1, col])
    return fig


# --------------------------------------------------------------------------
# Samples and histograms


def strategies(result: Any, weighted: bool = True, exposure: float = 0.0,
               fig: Figure | None = None) -> Figure:
    """The images of a bidirectional render's strategies (``mcsample.render
    (..., integrator="bdpt", strategies=True)``), as pbrt-v4's "visualize
    strategies": one row per path length (segments), one column per number
    of light vertices ``s`` (``t`` camera vertices), each tone-mapped with
    ``exposure``. ``weighted``: each strategy's MIS-weighted contribution
    (a row adds up to that length's light); else each strategy's estimate
    alone (every image of a row estimates the same light, with its own
    noise)."""
    images = getattr(result, "strategies", None)
    if not images:
        raise ValueError("result has no strategy images: render with integrator='bdpt', "
                         "strategies=True")
    depth = max(v.depth for v in images.values())
    columns = depth + 1
    h, w = next(iter(images.values())).weighted.shape[:2]
    if fig is None:
        fig = _figure(figsize=(1.8 * columns, 1.8 * depth * h / w + 0.6), layout="constrained")
    axes = fig.subplots(depth, columns, squeeze=False)
    for ax in axes.flat:
        ax.set_axis_off()
    for (s, t), v in sorted(images.items()):
        image(v.weighted if weighted else v.unweighted, exposure, ax=axes[v.depth - 1, s],
              title=f"s={s}, t={t}")
    fig.suptitle(f"bidirectional strategies ({'weighted' if weighted else 'unweighted'}); "
                 "rows: path length 1 .. " + str(depth))
    return fig


def samples(points: Any, domain: DomainLike = "square", projection: str = "flat",
            max_points: int = 4000, ax: Axes | None = None, **scatter: Any) -> Axes:
    """A scatter of samples on their domain (see :func:`mcsample.stats.make_domain`).

    Planar domains ("square", "disk", rectangles) are drawn as they are, with
    the domain's outline; an interval as points jittered vertically. On
    "sphere" and "hemisphere", ``projection="flat"`` unrolls the directions
    to (phi, cos theta), where a uniform density looks uniform (Archimedes),
    and ``projection="3d"`` draws them on the unit sphere. At most
    ``max_points`` points are drawn; ``scatter`` goes to ``ax.scatter`` (an
    array ``c`` of per-point colours is thinned with the points).
    """
    d = make_domain(domain)
    pts = np.asarray(points, dtype=np.float64)
    keep = _thin(len(pts), max_points)
    colours = scatter.get("c")
    if colours is not None and np.ndim(colours) >= 1 and len(colours) == len(pts):
        scatter["c"] = np.asarray(colours)[keep]  # per-point colours follow the thinning
    pts = pts[keep]
    scatter = {"s": 2, "alpha": 0.6, "linewidths": 0, **scatter}
    spherical = isinstance(d, SphericalDomain)
    if projection not in ("flat", "3d"):
        raise ValueError(f"projection = {projection!r}: expected 'flat' or '3d'")
    if projection == "3d":
        if not spherical:
            raise ValueError(f"projection = '3d' needs a sphere or hemisphere domain, got {d!r}")
        ax3d: Any = _axes(ax, projection="3d")
        phi, theta = np.meshgrid(np.linspace(-np.pi, np.pi, 25),
                                 np.linspace(0, np.pi if d.bounds[1][0] < 0 else np.pi / 2, 13))
        ax3d.plot_wireframe(np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                          np.cos(theta), color="0.8", linewidth=0.4)
        ax3d.scatter(pts[:, 0], pts[:, 1], pts[:, 2], **scatter)
        ax3d.set_box_aspect((1, 1, 1 if d.bounds[1][0] < 0 else 0.5))
        ax3d.set_xlabel("x")
        ax3d.set_ylabel("y")
        ax3d.set_zlabel("z")
        return ax3d
    ax = _axes(ax)
    (x0, x1), (y0, y1) = d.bounds
    if d.point_dim == 1:
        x = pts.reshape(-1)
        ax.scatter(x, np.random.default_rng(1).random(len(x)), **scatter)
        ax.set_xlim(x0, x1)
        ax.set_yticks([])
        ax.set_xlabel("x")
    elif spherical:
        xy = d.to_param(pts)
        ax.scatter(xy[:, 0], xy[:, 1], **scatter)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        xlabel, ylabel = _param_labels(d)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
    else:
        ax.scatter(pts[:, 0], pts[:, 1], **scatter)
        if d.bounds == ((-np.pi, np.pi), (0.0, 1.0)):  # the unit disk
            t = np.linspace(0, 2 * np.pi, 200)
            ax.plot(np.cos(t), np.sin(t), color="0.5", linewidth=0.8)
        else:
            ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="0.5", linewidth=0.8)
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
    return ax


def _param_labels(domain: Domain) -> tuple[str, str]:
    if isinstance(domain, SphericalDomain):
        return "φ", "cos θ" if domain.zoom == 1.0 else f"y (zoom {domain.zoom:g})"
    if domain.bounds == ((-np.pi, np.pi), (0.0, 1.0)):
        return "φ", "r²"
    return "x", "y"


def chi2(result: Chi2Result, axes: Sequence[Axes] | None = None) -> Figure:
    """A chi-square test drawn as Mitsuba's harness dumps it on failure:
    the histogram of the samples, the counts the pdf predicts per cell, and
    their difference (observed − expected, in samples per cell), over the
    domain's parameter box. ``result`` comes from
    :func:`mcsample.stats.chi2_test` or :func:`~mcsample.stats.two_sample_test`;
    ``axes`` may be three Axes to draw into."""
    if axes is None:
        axes = _figure(figsize=(13, 3.6), layout="constrained").subplots(1, 3)
    fig: Any = axes[0].figure
    obs, exp = np.asarray(result.histogram), np.asarray(result.expected)
    diff = obs - exp
    verdict = "passed" if result.passed else "FAILED"
    titles = (f"histogram ({int(obs.sum()):,} samples)", "expected (pdf integrated per cell)",
              f"observed − expected\np = {result.p_value:.3g}, {verdict}")
    (x0, x1), (y0, y1) = result.domain.bounds
    if result.domain.point_dim == 1:
        edges = np.linspace(x0, x1, obs.shape[1] + 1)
        centers, width = 0.5 * (edges[1:] + edges[:-1]), edges[1] - edges[0]
        axes[0].bar(centers, obs[0], width=width, color="C0")
        axes[1].bar(centers, exp[0], width=width, color="C1")
        axes[2].bar(centers, diff[0], width=width, color="C3")
        for ax in axes:
            ax.set_xlabel("x")
    else:
        xlabel, ylabel = _param_labels(result.domain)
        vmax = max(obs.max(), exp.max())
        limit = max(np.abs(diff).max(), 1e-12)
        for ax, data, kw in ((axes[0], obs, {"vmin": 0, "vmax": vmax}),
                             (axes[1], exp, {"vmin": 0, "vmax": vmax}),
                             (axes[2], diff, {"vmin": -limit, "vmax": limit, "cmap": "RdBu_r"})):
            im = ax.imshow(data, origin="lower", extent=(x0, x1, y0, y1), aspect="auto",
                           interpolation="nearest", **kw)
            fig.colorbar(im, ax=ax, label="samples per cell")
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
    for ax, title in zip(axes, titles):
        ax.set_title(title)
    return fig


# --------------------------------------------------------------------------
# Distributions


def distribution(dist: Any, axes: Sequence[Axes] | None = None) -> Figure:
    """A distribution's probabilities and cumulative distribution.

    Discrete1D / AliasTable: pmf (bars) and cdf (steps). PiecewiseConstant1D:
    pdf and cdf on its interval. Discrete2D / PiecewiseConstant2D: the pmf /
    pdf as an image and its marginal over rows. ``axes``: two Axes to draw
    into."""
    if axes is None:
        axes = _figure(figsize=(10, 3.6), layout="constrained").subplots(1, 2)
    fig: Any = axes[0].figure
    name = type(dist).__name__
    if hasattr(dist, "domain") and np.ndim(dist.domain) == 1:  # PiecewiseConstant1D
        a, b = dist.domain
        edges = np.linspace(a, b, len(dist) + 1)
        x = np.linspace(a, b, 64 * len(dist) + 1)
        axes[0].stairs(dist.pdf(0.5 * (edges[1:] + edges[:-1])), edges, fill=True, alpha=0.7)
        axes[1].plot(x, dist.cdf(x))
        axes[0].set_ylabel("pdf (per unit length)")
        axes[1].set_ylabel("cdf")
        for ax in axes:
            ax.set_xlabel("x")
    elif hasattr(dist, "shape"):  # 2D tables
        rows, cols = dist.shape
        if hasattr(dist, "domain"):
            (x0, x1), (y0, y1) = dist.domain
            gx, gy = np.meshgrid(x0 + (np.arange(cols) + 0.5) / cols * (x1 - x0),
                                 y0 + (np.arange(rows) + 0.5) / rows * (y1 - y0))
            table = dist.pdf(np.stack([gx.ravel(), gy.ravel()], 1)).reshape(rows, cols)
            label, extent = "pdf (per unit area)", (x0, x1, y1, y0)
            marginal = table.mean(axis=1) * (x1 - x0)
        else:
            table = dist.pmf()
            label, extent = "pmf", (-0.5, cols - 0.5, rows - 0.5, -0.5)
            marginal = table.sum(axis=1)
        im = axes[0].imshow(table, extent=extent, aspect="auto", interpolation="nearest")
        fig.colorbar(im, ax=axes[0], label=label)
        axes[0].set_xlabel("column")
        axes[0].set_ylabel("row")
        axes[1].bar(np.arange(rows), marginal)
        axes[1].set_xlabel("row")
        axes[1].set_ylabel("marginal")
    else:  # Discrete1D, AliasTable
        pmf = np.asarray(dist.pmf())
        i = np.arange(len(pmf))
        axes[0].bar(i, pmf)
        # P(X <= x) jumps by pmf[i] at x = i.
        axes[1].step(np.concatenate([[-0.5], i, [len(pmf) - 0.5]]),
                     np.concatenate([[0.0], np.cumsum(pmf), [np.sum(pmf)]]), where="post")
        axes[0].set_ylabel("pmf")
        axes[1].set_ylabel("cdf")
        for ax in axes:
            ax.set_xlabel("index")
    axes[0].set_title(name)
    return fig


# --------------------------------------------------------------------------
# Environment maps


class _EnvLayout:
    """An environment map's display plane: the lat-long or angular image as
    it is, a cube map as the horizontal cross (+y above; -x, +z, +x, -z;
    -y below), which is seamless in the OpenGL face orientation. Positions
    are in pixels, (x right, y down)."""

    # (column, row) of each face (+x, -x, +y, -y, +z, -z) in the cross.
    CROSS = ((2, 1), (0, 1), (1, 0), (1, 2), (1, 1), (3, 1))

    def __init__(self, env: Any):
        self.env = env
        self.mapping = env.mapping
        img = np.asarray(env.image, dtype=np.float64) * env.scale
        if self.mapping == "cube":
            r = img.shape[1]
            self.face_size = r
            self.image = np.full((3 * r, 4 * r, 3), np.nan)
            for face, (c, row) in enumerate(self.CROSS):
                self.image[row * r:(row + 1) * r, c * r:(c + 1) * r] = img[face]
        else:
            self.image = img
        self.height, self.width = self.image.shape[:2]

    def to_pixels(self, d: np.ndarray) -> np.ndarray:
        """World directions (n, 3) → display positions (n, 2)."""
        uv = np.asarray(self.env.dir_to_uv(d), dtype=np.float64)
        if self.mapping != "cube":
            return uv * [self.width, self.height]
        face = np.minimum(uv[:, 1].astype(np.int64), 5)
        cross = np.asarray(self.CROSS, dtype=np.float64)[face]
        r = self.face_size
        return np.stack([(cross[:, 0] + uv[:, 0]) * r,
                         (cross[:, 1] + uv[:, 1] - face) * r], axis=1)

    def pixel_directions(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The directions (h, w, 3) of the display pixels' centres, whether
        each pixel shows the sphere (h, w), and the map-plane area element
        |dω / d(x, y)| in steradians per pixel (h, w), by central
        differences of uv_to_dir."""
        h, w = self.height, self.width
        gx, gy = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
        if self.mapping == "cube":
            r = self.face_size
            face = np.full((h, w), -1)
            for f, (c, row) in enumerate(self.CROSS):
                face[row * r:(row + 1) * r, c * r:(c + 1) * r] = f
            valid = face >= 0
            uv = np.stack([gx / r % 1.0, np.maximum(face, 0) + gy / r % 1.0], axis=-1)
            scale = np.array([1.0 / r, 1.0 / r])
        else:
            uv = np.stack([gx / w, gy / h], axis=-1)
            valid = np.ones((h, w), dtype=bool)
            if self.mapping == "angular":
                valid = (2 * uv[..., 0] - 1) ** 2 + (2 * uv[..., 1] - 1) ** 2 < 1.0
            scale = np.array([1.0 / w, 1.0 / h])
        flat = uv.reshape(-1, 2)
        dirs = np.asarray(self.env.uv_to_dir(flat), dtype=np.float64)
        eps = 1e-4
        du = (np.asarray(self.env.uv_to_dir(flat + [eps, 0]))
              - np.asarray(self.env.uv_to_dir(flat - [eps, 0]))) / (2 * eps)
        dv = (np.asarray(self.env.uv_to_dir(flat + [0, eps]))
              - np.asarray(self.env.uv_to_dir(flat - [0, eps]))) / (2 * eps)
        area = np.linalg.norm(np.cross(du, dv), axis=1) * scale[0] * scale[1]
        return dirs.reshape(h, w, 3), valid, area.reshape(h, w)


def envmap(env: Any, n_samples: int = 2000, seed: int = 0, exposure: float = 0.0,
           density: str = "map", axes: Sequence[Axes] | None = None) -> Figure:
    """An environment map (any mapping; a cube map as a cross) in three
    panels: the tone-mapped radiance, its sampling density, and
    ``n_samples`` samples of ``env.sample`` over the image.

    ``density="map"`` draws the density per pixel of the map plane, pdf(ω) ·
    |dω/dA| — luminance times the mapping's Jacobian (sin θ for lat-long),
    what the sampling tables hold; ``density="solid_angle"`` draws pdf(ω)
    per steradian. Both on a log scale. ``axes``: three Axes to draw into."""
    from matplotlib.colors import LogNorm

    from ._core import uniform

    if density not in ("map", "solid_angle"):
        raise ValueError(f"density = {density!r}: expected 'map' or 'solid_angle'")
    layout = _EnvLayout(env)
    if axes is None:
        aspect = layout.width / layout.height
        axes = _figure(figsize=(7.8 * max(aspect, 1.0) + 1.5, 3.3),
                       layout="constrained").subplots(1, 3)
    fig: Any = axes[0].figure
    rgb = tonemap(layout.image, exposure)
    shown = np.concatenate([rgb, np.isfinite(layout.image[..., :1]).astype(np.float64)], -1)
    extent = (0, layout.width, layout.height, 0)
    for ax in (axes[0], axes[2]):
        ax.imshow(shown, extent=extent, interpolation="nearest")
    dirs, valid, area = layout.pixel_directions()
    pdf = np.asarray(env.pdf(dirs.reshape(-1, 3)), dtype=np.float64).reshape(valid.shape)
    if density == "map":
        pdf = pdf * area
    pdf = np.where(valid, pdf, np.nan)
    positive = pdf[np.isfinite(pdf) & (pdf > 0)]
    if positive.size:
        top = positive.max()
        norm = LogNorm(vmin=max(positive.min(), top * 1e-6), vmax=top)
        im = axes[1].imshow(np.where(pdf > 0, pdf, np.nan), extent=extent, norm=norm,
                            interpolation="nearest", cmap="inferno")
        fig.colorbar(im, ax=axes[1], shrink=0.8,
                     label="probability per pixel" if density == "map" else "pdf per sr")
    if n_samples:
        s = env.sample(uniform(n_samples, 2, seed=seed))
        keep = np.asarray(s.pdf) > 0
        xy = layout.to_pixels(np.asarray(s.direction)[keep])
        axes[2].scatter(xy[:, 0], xy[:, 1], s=3, c="cyan", linewidths=0, alpha=0.8)
    titles = (f"{env.mapping} radiance (exposure {exposure:+g})",
              "sampling density" + (" (map plane)" if density == "map" else " (per sr)"),
              f"{n_samples} samples")
    for ax, title in zip(axes, titles):
        ax.set_title(title)
        ax.set_xlim(0, layout.width)
        ax.set_ylim(layout.height, 0)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
    return fig


# --------------------------------------------------------------------------
# Phong lobes


def phong_lobe(wi: Any = (0.5, 0.0, 0.75 ** 0.5), exponents: Sequence[float] = (1, 10, 100, 1000),
               diffuse: Any = 0.0, specular: Any = 1.0, quantity: str = "pdf",
               normalize: bool = True, ax: Axes | None = None) -> Axes:
    """Phong lobes in the plane of incidence (the plane of ``wi`` and the
    normal +z; the x-z plane when wi is the normal), on polar axes with the
    normal up: ``quantity`` = "pdf" (the sampling density per sr), "brdf"
    (f_r) or "brdf_cos" (f_r cos θo, what is integrated), one curve per
    exponent, each scaled to a peak of 1 when ``normalize``. The incident
    direction and its mirror are drawn as lines. ``diffuse`` and
    ``specular`` are the Phong albedos (RGB or scalar); curves use the mean
    over channels."""
    from ._core import Phong

    if quantity not in ("pdf", "brdf", "brdf_cos"):
        raise ValueError(f"quantity = {quantity!r}: expected 'pdf', 'brdf' or 'brdf_cos'")
    w = np.asarray(wi, dtype=np.float64)
    w = w / np.linalg.norm(w)
    # In-plane axis: the tangent direction of wi (x when wi is the normal).
    t = np.array([w[0], w[1], 0.0])
    t = t / np.linalg.norm(t) if np.linalg.norm(t) > 1e-9 else np.array([1.0, 0.0, 0.0])
    polar: Any = _axes(ax, projection="polar")
    polar.set_theta_zero_location("N")
    polar.set_theta_direction(-1)
    polar.set_thetamin(-90)
    polar.set_thetamax(90)
    angle = np.linspace(-np.pi / 2, np.pi / 2, 2001)  # signed θo, positive toward +t
    wo = np.sin(angle)[:, None] * t + np.cos(angle)[:, None] * np.array([0, 0, 1.0])
    for n in exponents:
        phong = Phong(diffuse, specular, float(n))
        if quantity == "pdf":
            value = np.asarray(phong.pdf(w, wo), dtype=np.float64)
        else:
            value = np.asarray(phong.eval(w, wo), dtype=np.float64).mean(axis=1)
            if quantity == "brdf_cos":
                value = value * np.maximum(wo[:, 2], 0.0)
        if normalize and value.max() > 0:
            value = value / value.max()
        polar.plot(angle, value, label=f"n = {n:g}")
    theta_i = np.arctan2(w @ t, w[2])
    top = polar.get_ylim()[1]
    polar.plot([theta_i, theta_i], [0, top], "k--", linewidth=0.8, label="wi")
    polar.plot([-theta_i, -theta_i], [0, top], ":", color="0.4", linewidth=0.8, label="mirror")
    polar.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small")
    polar.set_title({"pdf": "sampling pdf", "brdf": "f_r", "brdf_cos": "f_r cos θo"}[quantity]
                 + (" (each scaled to peak 1)" if normalize else ""))
    return polar


# --------------------------------------------------------------------------
# Convergence


def convergence(n: Any, errors: Any, labels: Sequence[str] | None = None,
                slope: bool = True, order: float = 0.5, ax: Axes | None = None) -> Axes:
    """Error against sample count on log-log axes: ``errors`` is one curve
    (len(n),), several (k, len(n)), or a dict name → curve. ``slope`` draws
    the line N^(-order) through the first curve's first point for
    comparison: order ½, the 1/sqrt(N) of a Monte Carlo estimator's standard
    error (the default); order 1 for variances and (rel)MSE."""
    ax = _axes(ax)
    n = np.asarray(n, dtype=np.float64)
    if isinstance(errors, Mapping):
        labels = list(errors)
        curves = [np.asarray(v, dtype=np.float64) for v in errors.values()]
    else:
        arr = np.asarray(errors, dtype=np.float64)
        curves = list(arr) if arr.ndim == 2 else [arr]
    if labels is not None and len(labels) != len(curves):
        raise ValueError(f"{len(labels)} labels for {len(curves)} curves")
    for i, curve in enumerate(curves):
        if curve.shape != n.shape:
            raise ValueError(f"curve {i} has shape {curve.shape}, n has {n.shape}")
        ax.loglog(n, curve, "o-", ms=3, label=None if labels is None else labels[i])
    if slope:
        label = "∝ 1/√N" if order == 0.5 else f"∝ N^-{order:g}"
        ax.loglog(n, curves[0][0] * (n[0] / n) ** order, "k--", linewidth=0.8, label=label)
    if len(n) <= 10:  # label the measured counts themselves
        from matplotlib.ticker import NullFormatter

        ax.set_xticks(n, [f"{v:g}" for v in n])
        ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("N (samples)")
    ax.set_ylabel("error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    return ax
