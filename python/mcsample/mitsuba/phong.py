"""The energy-normalised Phong BRDF as a Mitsuba 3 BSDF plugin, written in
Dr.Jit independently of mcsample's Rust implementation (so that each checks
the other). Register it with :func:`register_phong`.

Same model and sampling as :class:`mcsample.Phong`:
f_r = rho_d / pi + rho_s (n + 2) / (2 pi) max(0, cos alpha)^n (alpha from the
mirror direction of wi), the diffuse part chosen with probability
max(rho_d) / (max(rho_d) + max(rho_s)) by ``sample1``, the direction placed
by ``sample2`` (a cosine-weighted direction, or a cos^n lobe around the
mirror direction), pdf the mixture of both densities. Mitsuba's ``eval``
includes the cosine factor.
"""

from __future__ import annotations

import math

#: The plugin's type name in scene dictionaries.
TYPE_NAME = "mcsample_phong"


def _constant_rgb(mi, value, name: str):
    """A plain RGB triple from a float, a sequence or a constant texture."""
    import drjit as dr

    if isinstance(value, mi.Texture):
        color = value.eval(dr.zeros(mi.SurfaceInteraction3f))
        return [dr.slice(color[k]) if hasattr(dr, "slice") else float(color[k][0])
                for k in range(3)]
    try:
        v = float(value)
        return [v, v, v]
    except TypeError:
        rgb = [float(c) for c in value]
    if len(rgb) != 3:
        raise ValueError(f"{name} must be a number or three numbers (RGB), got {value!r}")
    return rgb


def make_class(mi):
    """The BSDF class for the current Mitsuba variant."""
    import drjit as dr

    class McsamplePhong(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            kd = _constant_rgb(mi, props.get("diffuse_reflectance", 0.5), "diffuse_reflectance")
            ks = _constant_rgb(mi, props.get("specular_reflectance", 0.2), "specular_reflectance")
            n = float(props.get("exponent", 30.0))
            if not (n >= 0 and math.isfinite(n)):
                raise ValueError(f"exponent = {n}: must be finite and >= 0")
            for k in range(3):
                if kd[k] < 0 or ks[k] < 0 or kd[k] + ks[k] > 1:
                    raise ValueError(f"diffuse_reflectance[{k}] + specular_reflectance[{k}] = "
                                     f"{kd[k] + ks[k]}: must be in [0, 1]")
            self.kd, self.ks, self.n = mi.Color3f(kd), mi.Color3f(ks), n
            d, s = max(kd), max(ks)
            self.pd = d / (d + s) if d + s > 0 else 1.0
            flags = (mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection
                     | mi.BSDFFlags.FrontSide)
            self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide,
                                 mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = flags

        def _lobe(self, wi, wo):
            r = mi.Vector3f(-wi.x, -wi.y, wi.z)
            cos_alpha = dr.dot(r, wo)
            return dr.select(cos_alpha > 0, dr.power(dr.maximum(cos_alpha, 0.0), self.n), 0.0)

        def _pdf(self, wi, wo, lobe):
            diffuse = dr.maximum(mi.Frame3f.cos_theta(wo), 0.0) * dr.inv_pi
            return self.pd * diffuse + (1 - self.pd) * (self.n + 1) * dr.inv_two_pi * lobe

        def _value(self, wi, wo, lobe):
            cos_o = mi.Frame3f.cos_theta(wo)
            f = self.kd * dr.inv_pi + self.ks * ((self.n + 2) * dr.inv_two_pi * lobe)
            above = (mi.Frame3f.cos_theta(wi) > 0) & (cos_o > 0)
            return dr.select(above, f * cos_o, 0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = si.wi
            diffuse = sample1 < self.pd
            d = mi.warp.square_to_cosine_hemisphere(sample2)
            cos_t = dr.power(sample2.y, 1.0 / (self.n + 1))
            sin_t = dr.safe_sqrt(1 - cos_t * cos_t)
            sp, cp = dr.sincos(dr.two_pi * sample2.x)
            r = mi.Vector3f(-wi.x, -wi.y, wi.z)
            g = mi.Frame3f(r).to_world(mi.Vector3f(cp * sin_t, sp * sin_t, cos_t))
            wo = dr.select(diffuse, d, g)
            lobe = self._lobe(wi, wo)
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = wo
            bs.pdf = self._pdf(wi, wo, lobe)
            bs.eta = 1.0
            bs.sampled_component = dr.select(diffuse, mi.UInt32(0), mi.UInt32(1))
            bs.sampled_type = dr.select(diffuse, mi.UInt32(+mi.BSDFFlags.DiffuseReflection),
                                        mi.UInt32(+mi.BSDFFlags.GlossyReflection))
            value = self._value(wi, wo, lobe)
            weight = dr.select(active & (bs.pdf > 0), value / dr.maximum(bs.pdf, 1e-30), 0.0)
            return bs, weight

        def eval(self, ctx, si, wo, active=True):
            return self._value(si.wi, wo, self._lobe(si.wi, wo))

        def pdf(self, ctx, si, wo, active=True):
            return self._pdf(si.wi, wo, self._lobe(si.wi, wo))

        def eval_pdf(self, ctx, si, wo, active=True):
            lobe = self._lobe(si.wi, wo)
            return self._value(si.wi, wo, lobe), self._pdf(si.wi, wo, lobe)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return f"McsamplePhong[kd={self.kd}, ks={self.ks}, exponent={self.n}]"

    return McsamplePhong


_REGISTERED: set[str] = set()


def register_phong() -> str:
    """Registers mcsample's Phong BSDF for the current Mitsuba variant (set
    one first, e.g. with :func:`load`) and returns its type name,
    ``"mcsample_phong"``. Its keys are ``diffuse_reflectance`` and
    ``specular_reflectance`` (a float, an RGB triple or a constant
    texture) and ``exponent``; it is written in Dr.Jit, independently of
    the Rust :class:`mcsample.Phong`, with the same formula and sampling."""
    import mitsuba as mi

    variant = mi.variant()
    if variant is None:
        raise RuntimeError("set a Mitsuba variant first (mcsample.mitsuba.load())")
    if variant not in _REGISTERED:
        cls = make_class(mi)
        mi.register_bsdf(TYPE_NAME, lambda props: cls(props))
        _REGISTERED.add(variant)
    return TYPE_NAME
