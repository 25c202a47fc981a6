//! Light from infinitely far away: an environment map or a constant
//! environment, with its importance sampling.

use glam::Vec3A;
use std::sync::Arc;

use crate::envmap::{CellSampler, EnvMap, EnvSample};
use crate::math::luminance;
use crate::warp;

/// Light from infinitely far away.
#[derive(Clone, Debug)]
pub enum Environment {
    /// An environment map (sampled by its own importance sampling).
    Map(Arc<EnvMap>),
    /// The same radiance from every direction (sampled uniformly on the
    /// sphere, pdf `1/(4π)`).
    Constant([f64; 3]),
}

impl Environment {
    /// Radiance arriving from world direction `d`.
    #[inline]
    pub fn eval(&self, d: Vec3A) -> [f32; 3] {
        match self {
            Environment::Map(env) => env.eval(d.to_array()),
            Environment::Constant(l) => l.map(|v| v as f32),
        }
    }

    /// [`Environment::eval`] for a batch of directions.
    pub fn eval_into(&self, d: &[[f32; 3]], out: &mut [[f32; 3]]) {
        match self {
            Environment::Map(env) => {
                env.eval_into(d, out, |_| true);
            }
            Environment::Constant(l) => out.fill(l.map(|v| v as f32)),
        }
    }

    /// Density of [`Environment::sample`] at `d`, per steradian.
    #[inline]
    pub fn pdf(&self, d: Vec3A) -> f32 {
        match self {
            Environment::Map(env) => env.pdf(d.as_dvec3().to_array()) as f32,
            Environment::Constant(_) => 0.25 * std::f32::consts::FRAC_1_PI,
        }
    }

    /// A direction, its density per steradian and its radiance. A map
    /// draws by `cells` (its [`CellSampler`], with 64 random bits for the
    /// cell, `u` placing the point in it) where it has one, else by
    /// [`EnvMap::sample`] of `u`.
    #[inline]
    pub fn sample(
        &self,
        u: [f32; 2],
        cells: Option<(&CellSampler, u64)>,
    ) -> (Vec3A, f32, [f32; 3]) {
        match self {
            Environment::Map(env) => match cells {
                Some((cells, bits)) => {
                    let s = cells.sample(env, bits, u);
                    (Vec3A::from(s.direction), s.pdf, s.radiance)
                }
                None => Self::of_inversion(env.sample(u.map(f64::from))),
            },
            Environment::Constant(l) => {
                let d = warp::square_to_uniform_sphere(u);
                (Vec3A::from(d), self.pdf(Vec3A::Z), l.map(|v| v as f32))
            }
        }
    }

    /// [`Environment::sample`] of a map's sample `s` by inversion (in
    /// `f64`): rounded to `f32`, its radiance as weight · pdf in `f32`
    /// rather than rounded from `f64`, so that these renders keep their
    /// bits.
    #[inline]
    pub(super) fn of_inversion(s: EnvSample) -> (Vec3A, f32, [f32; 3]) {
        let s = s.cast::<f32>();
        let radiance = s.weight.map(|w| w * s.pdf);
        (Vec3A::from(s.direction), s.pdf, radiance)
    }

    /// `∫ Y(L(ω)) dω` over the sphere, by the midpoint rule on a 256 × 128
    /// grid in (φ, cos θ) (for choosing among lights; it need not be exact).
    pub(crate) fn luminance_integral(&self) -> f64 {
        let (nx, ny) = (256, 128);
        let mut sum = 0.0;
        for j in 0..ny {
            let z = 1.0 - 2.0 * (j as f64 + 0.5) / ny as f64;
            let r = (1.0 - z * z).sqrt();
            for i in 0..nx {
                let phi = 2.0 * std::f64::consts::PI * (i as f64 + 0.5) / nx as f64;
                let d = Vec3A::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                sum += luminance(self.eval(d).map(f64::from));
            }
        }
        sum * 4.0 * std::f64::consts::PI / (nx * ny) as f64
    }
}
