//! The energy-normalised ("physically plausible") modified Phong BRDF with
//! importance sampling of its diffuse and glossy parts.
//!
//! Directions are in the local shading frame (normal = +z); `wi` points
//! toward the viewer, `wo` is the sampled direction; both unit length.

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::math::{Real, V3, dot, luminance};
use crate::simd;
use crate::warp;

/// How [`Phong::sample`] picks the diffuse or the glossy part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    /// `p_d = max(ρd) / (max(ρd) + max(ρs))` over the RGB channels (the
    /// default).
    Max,
    /// `p_d = Y(ρd) / (Y(ρd) + Y(ρs))` with Rec. 709 luminance Y (Mitsuba
    /// 0.6's rule).
    Luminance,
}

/// The modified Phong BRDF of Lafortune and Willems, normalised so that it
/// conserves energy when `ρd + ρs ≤ 1`.
///
/// # BRDF
/// `f_r(wi, wo) = ρd/π + ρs·(n + 2)/(2π)·max(0, cos α)ⁿ`, where α is the
/// angle between `wo` and the mirror direction `r = 2(wi·n)n − wi`; 0 when
/// `wi` or `wo` is below the surface. No cosine factor.
///
/// # Sampling and density
/// The diffuse part (probability `p_d`, see [`Selection`]) draws a
/// cosine-weighted direction; the glossy part (`p_s = 1 − p_d`) a cosⁿ lobe
/// around `r`, in a frame built on `r`. Whichever part drew `wo`, its
/// density per steradian is the mixture
/// `p(wo) = p_d·max(cos θo, 0)/π + p_s·(n + 1)/(2π)·max(0, cos α)ⁿ`,
/// which is positive below the surface where the lobe reaches there (such
/// samples carry weight 0).
///
/// # References
/// E. Lafortune, Y. Willems, "Using the Modified Phong Reflectance Model for
/// Physically Based Rendering", KU Leuven report CW197, 1994.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    diffuse: [f64; 3],
    specular: [f64; 3],
    exponent: f64,
    diffuse_probability: f64,
}

/// One sample of [`Phong::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhongSample<F> {
    /// The sampled direction (local frame, unit length).
    pub wo: V3<F>,
    /// Its density per steradian (the mixture, see [`Phong`]).
    pub pdf: F,
    /// `f_r(wi, wo)·cos θo / pdf` per RGB channel; 0 below the surface.
    pub weight: V3<F>,
    /// 0 for the diffuse part, 1 for the glossy part.
    pub component: u8,
}

/// The arrays a batch of [`PhongView::sample_rows`] writes: each sample's
/// parts into their own array, as a caller's separate outputs want them;
/// the component in any integer type `C`.
#[derive(Debug)]
pub struct PhongSamples<'a, F, C> {
    /// The sampled directions.
    pub wo: &'a mut [V3<F>],
    /// Their densities per steradian.
    pub pdf: &'a mut [F],
    /// `f_r·cos θo / pdf` per RGB channel.
    pub weight: &'a mut [V3<F>],
    /// 0 for the diffuse part, 1 for the glossy part.
    pub component: &'a mut [C],
}

/// The largest lobe exponent: `f_r`'s constants `ρs·(n + 2)/2π` stay
/// finite in `f32`, so a masked `f_r` is 0, never `∞·0`. (Far past any
/// lobe a float can resolve: `cosⁿ` of the nearest angle below 1 is 0.)
pub const MAX_EXPONENT: f64 = 1e30;

/// The number of [`Phong::view_terms`].
pub(crate) const VIEW_TERMS: usize = 9;

/// Rows per block of [`PhongView::sample_rows`]: its numbers and samples
/// stay in the L1 cache.
const SAMPLE_BLOCK: usize = 256;

impl Phong {
    /// A Phong BRDF with RGB reflectances `diffuse` (ρd) and `specular` (ρs)
    /// and the lobe exponent `n`.
    ///
    /// # Errors
    /// [`Error::Element`] for a reflectance that is negative or not finite,
    /// [`Error::NotEnergyConserving`] if `ρd + ρs > 1` in a channel, and
    /// [`Error::Parameter`] for an exponent outside `[0,`
    /// [`MAX_EXPONENT`]`]`.
    pub fn new(
        diffuse: [f64; 3],
        specular: [f64; 3],
        exponent: f64,
        selection: Selection,
    ) -> Result<Self> {
        for (arg, rho) in [("diffuse", diffuse), ("specular", specular)] {
            if let Some(k) = rho.iter().position(|&v| !(v >= 0.0 && v.is_finite())) {
                return Err(Error::Element {
                    arg,
                    index: format!("[{k}]"),
                    value: rho[k],
                    requirement: "reflectances must be finite and >= 0".into(),
                });
            }
        }
        if let Some(k) = (0..3).find(|&k| diffuse[k] + specular[k] > 1.0) {
            return Err(Error::NotEnergyConserving {
                channel: k,
                sum: diffuse[k] + specular[k],
            });
        }
        if !(0.0..=MAX_EXPONENT).contains(&exponent) {
            return Err(Error::Parameter {
                arg: "exponent",
                value: exponent,
                requirement: "must be in [0, 1e30]",
            });
        }
        let (d, s) = match selection {
            Selection::Max => (max3(diffuse), max3(specular)),
            Selection::Luminance => (luminance(diffuse), luminance(specular)),
        };
        // A black material samples the diffuse part (its weight is 0).
        let diffuse_probability = if d + s > 0.0 { d / (d + s) } else { 1.0 };
        Ok(Phong {
            diffuse,
            specular,
            exponent,
            diffuse_probability,
        })
    }

    /// ρd.
    pub fn diffuse(&self) -> [f64; 3] {
        self.diffuse
    }

    /// ρs.
    pub fn specular(&self) -> [f64; 3] {
        self.specular
    }

    /// The lobe exponent n.
    pub fn exponent(&self) -> f64 {
        self.exponent
    }

    /// The probability `p_d` of sampling the diffuse part.
    pub fn diffuse_probability(&self) -> f64 {
        self.diffuse_probability
    }

    /// Whether the BRDF has a glossy part (`ρs ≠ 0`). Without one, `p_d =
    /// 1` and the lobe's terms are multiplied by ±0, so that
    /// [`PhongView::eval_pdf_diffuse`] and [`PhongView::sample_diffuse`]
    /// give its values. (A `ρs` so small that its terms round to 0 in
    /// `f32` is glossy here, though [`PhongView::lobe_if_glossy`] skips
    /// its lobe: its rows take the general kernel, which is right for any
    /// row.)
    #[inline]
    pub(crate) fn is_glossy(&self) -> bool {
        self.specular.iter().any(|&s| s != 0.0)
    }

    /// The BRDF seen from `wi`: what every evaluation and sample for that
    /// `wi` shares, computed once in the kernel's float type.
    #[inline(always)]
    pub fn view<F: Real>(&self, wi: V3<F>) -> PhongView<F> {
        PhongView::from_terms(wi, self.view_terms())
    }

    /// The terms of [`Phong::view`] that do not depend on `wi`, in `F`, as
    /// one row of numbers: `[n, p_d, ρd/π (3), ρs·(n + 2)/(2π) (3), (n +
    /// 1)/(2π)]`. A batch kernel over the views of several BRDFs reads
    /// them with its other numbers ([`PhongView::from_terms`]).
    #[inline(always)]
    pub(crate) fn view_terms<F: Real>(&self) -> [F; VIEW_TERMS] {
        let n = self.exponent;
        let inv_pi = std::f64::consts::FRAC_1_PI;
        let mut terms = [0.0; VIEW_TERMS];
        terms[0] = n;
        terms[1] = self.diffuse_probability;
        terms[2..5].copy_from_slice(&self.diffuse.map(|v| v * inv_pi));
        terms[5..8].copy_from_slice(&self.specular.map(|v| v * (n + 2.0) * 0.5 * inv_pi));
        terms[8] = (n + 1.0) * 0.5 * inv_pi;
        terms.map(F::c)
    }

    /// The BRDF value `f_r(wi, wo)` per RGB channel (no cosine).
    #[inline(always)]
    pub fn eval<F: Real>(&self, wi: V3<F>, wo: V3<F>) -> V3<F> {
        self.view(wi).eval(wo)
    }

    /// The density of [`Phong::sample`] at `wo`, per steradian.
    #[inline(always)]
    pub fn pdf<F: Real>(&self, wi: V3<F>, wo: V3<F>) -> F {
        self.view(wi).pdf(wo)
    }

    /// A direction drawn from the mixture for `wi`: `u[2]` picks the part,
    /// `u[0..2]` place the direction. `u` in `[0, 1]³`.
    #[inline(always)]
    pub fn sample<F: Real>(&self, wi: V3<F>, u: [F; 3]) -> PhongSample<F> {
        self.view(wi).sample(u)
    }
}

/// A [`Phong`] BRDF for one incident direction `wi`, with the mirror
/// direction, its frame and the constants of `f_r` and of the density
/// precomputed: batches that share `wi` build it once, outside their loop
/// (which then holds only the per-`wo` work and vectorises).
#[derive(Clone, Copy, Debug)]
pub struct PhongView<F> {
    wi_above: bool,
    mirror: V3<F>,
    mirror_frame: Frame<F>,
    exponent: F,
    diffuse_probability: F,
    /// `ρd/π`.
    diffuse: V3<F>,
    /// `ρs·(n + 2)/(2π)`.
    specular: V3<F>,
    /// `(n + 1)/(2π)`.
    glossy_norm: F,
}

impl<F: Real> PhongView<F> {
    /// The view from `wi` of the BRDF whose [`Phong::view_terms`] are
    /// `terms`: [`Phong::view`], without branches (for a batch of views at
    /// SIMD width as for one).
    #[inline(always)]
    pub(crate) fn from_terms(wi: V3<F>, terms: [F; VIEW_TERMS]) -> Self {
        let [exponent, diffuse_probability, parts @ .., glossy_norm] = terms;
        let [d0, d1, d2, s0, s1, s2] = parts;
        let mirror = reflect(wi);
        PhongView {
            wi_above: wi[2] > F::zero(),
            mirror,
            mirror_frame: Frame::from_normal(mirror),
            exponent,
            diffuse_probability,
            diffuse: [d0, d1, d2],
            specular: [s0, s1, s2],
            glossy_norm,
        }
    }

    /// `(f_r(wi, wo), pdf(wo))`, as [`PhongView::eval`] and
    /// [`PhongView::pdf`] (one power for both), without branches.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: V3<F>) -> (V3<F>, F) {
        let lobe = self.lobe(wo);
        (self.eval_with_lobe(wo, lobe), self.pdf_with_lobe(wo, lobe))
    }

    /// `max(0, cos α)ⁿ`, with α between `wo` and the mirror of `wi`.
    #[inline(always)]
    fn lobe(&self, wo: V3<F>) -> F {
        let cos_alpha = dot(self.mirror, wo);
        if cos_alpha > F::zero() {
            F::pow_positive(cos_alpha.min(F::one()), self.exponent)
        } else {
            F::zero()
        }
    }

    /// `f_r(wi, wo)` per RGB channel (no cosine).
    #[inline(always)]
    pub fn eval(&self, wo: V3<F>) -> V3<F> {
        self.eval_with_lobe(wo, self.lobe(wo))
    }

    /// The density of [`PhongView::sample`] at `wo`, per steradian.
    #[inline(always)]
    pub fn pdf(&self, wo: V3<F>) -> F {
        self.pdf_with_lobe(wo, self.lobe(wo))
    }

    #[inline(always)]
    fn eval_with_lobe(&self, wo: V3<F>, lobe: F) -> V3<F> {
        // Masked by a product, not a branch: LLVM would move the loads of
        // the two terms behind a branch, and a loop with loads it cannot
        // prove readable on every lane stays scalar. (`f` is finite and
        // ≥ 0, so `f·0 = +0` and `f·1 = f`, bit for bit.)
        let above = if self.wi_above && wo[2] > F::zero() {
            F::one()
        } else {
            F::zero()
        };
        std::array::from_fn(|k| (self.diffuse[k] + self.specular[k] * lobe) * above)
    }

    #[inline(always)]
    fn pdf_with_lobe(&self, wo: V3<F>, lobe: F) -> F {
        let pd = self.diffuse_probability;
        let diffuse = warp::square_to_cosine_hemisphere_pdf(wo);
        pd * diffuse + (F::one() - pd) * self.glossy_norm * lobe
    }

    /// A direction drawn from the mixture: `u[2]` picks the part, `u[0..2]`
    /// place the direction. `u` in `[0, 1]³`.
    #[inline(always)]
    pub fn sample(&self, u: [F; 3]) -> PhongSample<F> {
        let diffuse = u[2] < self.diffuse_probability;
        // Both candidates, then a select: the loop over samples stays
        // branch-free.
        let d = warp::square_to_cosine_hemisphere([u[0], u[1]]);
        let local = warp::square_to_cosine_power_hemisphere([u[0], u[1]], self.exponent);
        let g = self.mirror_frame.to_world(local);
        let wo = if diffuse { d } else { g };
        self.finish_sample(wo, self.lobe(wo), diffuse)
    }

    /// [`PhongView::sample`] of `prepare(row)` for each of `rows` into
    /// `out`, in blocks of `SAMPLE_BLOCK` rows: the numbers of a block
    /// made (a caller checks and clamps them there), its samples computed
    /// at SIMD width ([`simd::map_rows`]), then spread into the arrays of
    /// `out`.
    ///
    /// The kernel is large (two powers, two sines and cosines, a frame),
    /// and whether LLVM vectorises it for AVX2 has been seen to depend on
    /// code elsewhere in the crate (a binding that filled an `N`-row buffer
    /// through the same kernel ran one lane at a time). After a change,
    /// compare `python -m mcsample bench --only phong` with the same run
    /// under `MCSAMPLE_SIMD=baseline`: the vectorised build must be the
    /// faster one.
    ///
    /// # Panics
    /// If an array of `out` is shorter than `rows`.
    pub fn sample_rows<R, C: From<u8>>(
        &self,
        rows: &[R],
        mut prepare: impl FnMut(&R) -> [F; 3],
        out: PhongSamples<'_, F, C>,
    ) {
        let kernel = {
            #[inline(always)]
            |u: [F; 3]| {
                let s = self.sample(u);
                let ([x, y, z], [r, g, b]) = (s.wo, s.weight);
                [x, y, z, s.pdf, r, g, b, F::c(f64::from(s.component))]
            }
        };
        let simd::OnLines(us) = &mut simd::OnLines([[F::zero(); 3]; SAMPLE_BLOCK]);
        let simd::OnLines(samples) = &mut simd::OnLines([[F::zero(); 8]; SAMPLE_BLOCK]);
        for (b, rows) in rows.chunks(SAMPLE_BLOCK).enumerate() {
            let (us, samples) = (&mut us[..rows.len()], &mut samples[..rows.len()]);
            for (u, row) in us.iter_mut().zip(rows) {
                *u = prepare(row);
            }
            simd::map_rows(samples, us, &kernel, |_| true, false);
            for (k, s) in (b * SAMPLE_BLOCK..).zip(samples.iter()) {
                out.wo[k] = [s[0], s[1], s[2]];
                out.pdf[k] = s[3];
                out.weight[k] = [s[4], s[5], s[6]];
                out.component[k] = C::from(u8::from(s[7] > F::zero()));
            }
        }
    }

    /// [`PhongView::eval_pdf`] of a BRDF without a glossy part
    /// ([`Phong::is_glossy`]), bit for bit, without the lobe: `f_r = ρd/π`
    /// above the surface, `pdf = max(cos θ_o, 0)/π`. (The lobe's terms
    /// vanish there whatever its value, which is finite: `ρs·lobe = ±0`
    /// as `ρs·0`, and `(1 − p_d)·norm·lobe = +0` with `p_d = 1` and the
    /// finite `norm = (n + 1)/(2π)`, so that no power is taken.)
    #[inline(always)]
    pub(crate) fn eval_pdf_diffuse(&self, wo: V3<F>) -> (V3<F>, F) {
        (
            self.eval_with_lobe(wo, F::zero()),
            self.pdf_with_lobe(wo, F::zero()),
        )
    }

    /// [`PhongView::sample`] of `[u[0], u[1], part]` for a BRDF without a
    /// glossy part, bit for bit for every `part < 1` (which every sampler's
    /// numbers are): `p_d = 1` picks the diffuse part, the
    /// cosine-weighted direction of `u`, of density `cos θ_o/π` and weight
    /// `ρd` (neither the glossy candidate nor the lobe computed). A `part`
    /// of 1 or more, or NaN, would have `sample` take the glossy one.
    #[inline(always)]
    pub(crate) fn sample_diffuse(&self, u: [F; 2]) -> PhongSample<F> {
        self.finish_sample(warp::square_to_cosine_hemisphere(u), F::zero(), true)
    }

    /// The sample at `wo`, drawn by the diffuse part or not, where the lobe
    /// is `lobe`: its mixture density and weight.
    #[inline(always)]
    fn finish_sample(&self, wo: V3<F>, lobe: F, diffuse: bool) -> PhongSample<F> {
        let pdf = self.pdf_with_lobe(wo, lobe);
        let f = self.eval_with_lobe(wo, lobe);
        let scale = if pdf > F::zero() {
            wo[2].max(F::zero()) / pdf
        } else {
            F::zero()
        };
        PhongSample {
            wo,
            pdf,
            weight: f.map(|v| v * scale),
            component: u8::from(!diffuse),
        }
    }
}

/// One sample at a time, as bidirectional path tracing draws them: the
/// same densities and values as [`PhongView::sample`], [`PhongView::eval`]
/// and [`PhongView::pdf`], bit for bit, with branches where those are
/// branch-free for vectorised batches. Only the chosen part's direction is
/// drawn, and a BRDF without a glossy part (`ρs = 0`) skips its lobe, a
/// power.
impl<F: Real> PhongView<F> {
    /// [`PhongView::lobe`], or 0 without looking when there is no glossy
    /// part (whose terms it would multiply by 0: `ρs = 0`, so `f_r`'s
    /// glossy constant and `p_s` are 0). Not `p_d = 1`: `p_d` rounds to 1
    /// in `f32` for a glossy part below about `10⁻⁸` of the diffuse one,
    /// whose lobe still counts in `f_r`.
    #[inline(always)]
    fn lobe_if_glossy(&self, wo: V3<F>) -> F {
        if self.specular.iter().any(|&s| s > F::zero()) {
            self.lobe(wo)
        } else {
            F::zero()
        }
    }

    /// `(f_r(wi, wo), pdf(wo))`, as [`PhongView::eval`] and
    /// [`PhongView::pdf`].
    #[inline]
    pub fn eval_pdf_one(&self, wo: V3<F>) -> (V3<F>, F) {
        let lobe = self.lobe_if_glossy(wo);
        (self.eval_with_lobe(wo, lobe), self.pdf_with_lobe(wo, lobe))
    }

    /// A sample as [`PhongView::sample`] of `[u[0], u[1], part]`: the part
    /// by `part`, the direction by the pair `u` (named apart, so that a
    /// caller cannot take a direction from the part's number).
    #[inline]
    pub fn sample_one(&self, part: F, u: [F; 2]) -> PhongSample<F> {
        let diffuse = part < self.diffuse_probability;
        let wo = if diffuse {
            warp::square_to_cosine_hemisphere(u)
        } else {
            let local = warp::square_to_cosine_power_hemisphere(u, self.exponent);
            self.mirror_frame.to_world(local)
        };
        self.finish_sample(wo, self.lobe_if_glossy(wo), diffuse)
    }
}

#[inline(always)]
fn max3(v: [f64; 3]) -> f64 {
    v[0].max(v[1]).max(v[2])
}

/// The mirror direction of `wi` about the normal +z: `(−x, −y, z)`.
#[inline(always)]
fn reflect<F: Real>(wi: V3<F>) -> V3<F> {
    [-wi[0], -wi[1], wi[2]]
}

#[cfg(test)]
mod tests;
