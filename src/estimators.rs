//! Monte Carlo estimators of the light an environment map delivers to a
//! point: irradiance on a surface, and radiance reflected by a Phong
//! surface, each by several sampling strategies and their MIS combination.
//!
//! An estimate averages `n` independent evaluations `f_i`; its standard
//! error is `s/√n` with `s²` the sample variance. Sample `i` draws its
//! uniform numbers from the PCG32 stream of `seed` advanced to
//! `i · draws`, so the result is the same bits whatever the thread count.
//!
//! # Irradiance `E = ∫ L(ω) max(0, n·ω) dω`
//! - uniform: `ω` uniform on the hemisphere of `n`, `f = L cos θ · 2π`;
//! - cosine: `ω` cosine-weighted, `f = L π`;
//! - emitter: `ω` from the map, `f = (L/p_env) cos⁺ θ`;
//! - mis: one cosine and one emitter sample, each weighted by the heuristic
//!   against the other's density (Veach's multi-sample model).
//!
//! # Reflected radiance `L_r(ωi) = ∫ L(ω) f_r(ωi, ω) cos⁺ θ dω`
//! With the Phong BRDF in the frame of `n`: bsdf (its own sampling), emitter
//! (the map's), and mis of the two.

use crate::envmap::EnvMap;
use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::math::{V3, dot};
use crate::mis::Heuristic;
use crate::parallel;
use crate::phong::Phong;
use crate::rng::Rng;
use crate::warp;
use std::f64::consts::PI;
use std::sync::Mutex;

/// A sampling strategy. The renderer's [`crate::render::Strategy`] has the
/// same names for the same ideas (`Bsdf`, `Emitter`, `Mis`) and lacks the
/// two hemisphere strategies, which only make sense for irradiance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Uniform directions on the hemisphere (irradiance only).
    Uniform,
    /// Cosine-weighted directions (irradiance only).
    Cosine,
    /// The BRDF's own sampling (reflected radiance only).
    Bsdf,
    /// The emitter's importance sampling (here the environment map's).
    Emitter,
    /// MIS of the two applicable strategies (cosine or BSDF, and emitter).
    Mis,
}

impl Strategy {
    /// The name used in the Python API: `"uniform"`, `"cosine"`, `"bsdf"`,
    /// `"emitter"`, `"mis"`.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Uniform => "uniform",
            Strategy::Cosine => "cosine",
            Strategy::Bsdf => "bsdf",
            Strategy::Emitter => "emitter",
            Strategy::Mis => "mis",
        }
    }
}

/// How to estimate: `n` evaluations by `strategy` (MIS weights by
/// `heuristic`), random numbers from the stream of `seed`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    /// Number of evaluations, at least 1.
    pub n: usize,
    /// The sampling strategy.
    pub strategy: Strategy,
    /// The MIS heuristic (for [`Strategy::Mis`]).
    pub heuristic: Heuristic,
    /// Seed of the PCG32 stream.
    pub seed: u64,
}

/// A Monte Carlo estimate of an RGB quantity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The mean of the evaluations.
    pub value: V3<f64>,
    /// Its standard error, `s/√n`.
    pub stderr: V3<f64>,
    /// The number of evaluations.
    pub n: usize,
}

/// Running mean and sum of squared deviations (Welford), merged in a fixed
/// order (Chan et al.).
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    n: f64,
    mean: V3<f64>,
    m2: V3<f64>,
}

impl Moments {
    #[inline(always)]
    fn push(&mut self, f: V3<f64>) {
        self.n += 1.0;
        for (k, &x) in f.iter().enumerate() {
            let delta = x - self.mean[k];
            self.mean[k] += delta / self.n;
            self.m2[k] += delta * (x - self.mean[k]);
        }
    }

    fn merge(self, other: Moments) -> Moments {
        let n = self.n + other.n;
        if n == 0.0 {
            return self;
        }
        let mut out = Moments {
            n,
            ..Moments::default()
        };
        for k in 0..3 {
            let delta = other.mean[k] - self.mean[k];
            out.mean[k] = self.mean[k] + delta * other.n / n;
            out.m2[k] = self.m2[k] + other.m2[k] + delta * delta * self.n * other.n / n;
        }
        out
    }
}

impl Plan {
    /// The mean and standard error of `f(rng)` over `n` evaluations, each
    /// with its own stretch of `draws` numbers of the stream of `seed`.
    ///
    /// # Errors
    /// [`Error::Integer`] for `n = 0`.
    fn estimate(self, draws: u64, f: impl Fn(&mut Rng) -> V3<f64> + Sync) -> Result<Estimate> {
        let Plan { n, seed, .. } = self;
        if n == 0 {
            return Err(Error::Integer {
                arg: "n",
                value: "0".into(),
                requirement: "must be at least 1".into(),
            });
        }
        let base = Rng::new(seed, 0);
        let parts = Mutex::new(Vec::new());
        parallel::for_each_chunk(n, (), |range, ()| {
            // One partial sum per block of CHUNK items, whatever the range a
            // thread is handed: the same sums in the same order on any pool.
            let mut local = Vec::new();
            for start in range.clone().step_by(parallel::CHUNK) {
                let mut rng = base.jumped(start as u64 * draws);
                let mut m = Moments::default();
                for _ in start..(start + parallel::CHUNK).min(range.end) {
                    m.push(f(&mut rng));
                }
                local.push((start, m));
            }
            parts
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .extend(local);
            true
        })?;
        let mut parts = parts.into_inner().unwrap_or_else(|p| p.into_inner());
        parts.sort_by_key(|p| p.0);
        let m = parts
            .into_iter()
            .fold(Moments::default(), |acc, (_, m)| acc.merge(m));
        let stderr = if n > 1 {
            m.m2.map(|v| (v / (m.n - 1.0) / m.n).sqrt())
        } else {
            [f64::INFINITY; 3]
        };
        Ok(Estimate {
            value: m.mean,
            stderr,
            n,
        })
    }
}

/// `v` normalised.
///
/// # Errors
/// [`Error::Parameter`] naming `arg` for a zero or non-finite vector.
fn unit(arg: &'static str, v: V3<f64>) -> Result<V3<f64>> {
    let len = dot(v, v).sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return Err(Error::Parameter {
            arg,
            value: len,
            requirement: "must be finite and non-zero (its length is shown)",
        });
    }
    Ok(v.map(|x| x / len))
}

fn unsupported(strategy: Strategy, allowed: &str) -> Error {
    Error::Choice {
        arg: "strategy",
        value: strategy.name().into(),
        requirement: format!("must be {allowed}"),
    }
}

#[inline(always)]
fn scaled(v: V3<f64>, s: f64) -> V3<f64> {
    v.map(|x| x * s)
}

#[inline(always)]
fn add(a: V3<f64>, b: V3<f64>) -> V3<f64> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
fn next2(rng: &mut Rng) -> [f64; 2] {
    [rng.next_float(), rng.next_float()]
}

/// The irradiance at a surface of unit `normal` (world) lit by `env`.
///
/// # Errors
/// [`Error::Integer`] for `n = 0`, [`Error::Parameter`] for a zero or
/// non-finite normal, [`Error::Choice`] for [`Strategy::Bsdf`].
pub fn irradiance(env: &EnvMap, normal: V3<f64>, plan: Plan) -> Result<Estimate> {
    let (normal, heuristic) = (unit("normal", normal)?, plan.heuristic);
    let frame = Frame::from_normal(normal);
    let cosine_pdf = |d: V3<f64>| dot(d, normal).max(0.0) / PI;
    match plan.strategy {
        Strategy::Uniform => plan.estimate(2, |rng| {
            let d = frame.to_world(warp::square_to_uniform_hemisphere(next2(rng)));
            scaled(env.eval(d), dot(d, normal).max(0.0) * 2.0 * PI)
        }),
        Strategy::Cosine => plan.estimate(2, |rng| {
            let local = warp::square_to_cosine_hemisphere(next2(rng));
            let f = if local[2] > 0.0 { PI } else { 0.0 };
            scaled(env.eval(frame.to_world(local)), f)
        }),
        Strategy::Emitter => plan.estimate(2, |rng| {
            let s = env.sample(next2(rng));
            scaled(s.weight, dot(s.direction, normal).max(0.0))
        }),
        Strategy::Mis => plan.estimate(4, |rng| {
            let d = frame.to_world(warp::square_to_cosine_hemisphere(next2(rng)));
            let p = cosine_pdf(d);
            let from_cosine = if p > 0.0 {
                let w = heuristic.weight(p, env.pdf(d));
                scaled(env.eval(d), w * dot(d, normal) / p)
            } else {
                [0.0; 3]
            };
            let s = env.sample(next2(rng));
            let w = heuristic.weight(s.pdf, cosine_pdf(s.direction));
            add(
                from_cosine,
                scaled(s.weight, w * dot(s.direction, normal).max(0.0)),
            )
        }),
        Strategy::Bsdf => Err(unsupported(
            plan.strategy,
            r#""uniform", "cosine", "emitter" or "mis""#,
        )),
    }
}

/// The radiance a Phong surface of unit `normal` (world) reflects toward the
/// world direction `wi` under `env`.
///
/// # Errors
/// As [`irradiance`], also for a zero or non-finite `wi`, and
/// [`Error::Choice`] for [`Strategy::Uniform`] and [`Strategy::Cosine`].
pub fn reflected_radiance(
    env: &EnvMap,
    phong: &Phong,
    normal: V3<f64>,
    wi: V3<f64>,
    plan: Plan,
) -> Result<Estimate> {
    let (normal, wi) = (unit("normal", normal)?, unit("wi", wi)?);
    let heuristic = plan.heuristic;
    let frame = Frame::from_normal(normal);
    // The BRDF seen from wi, built once for all n samples.
    let view = phong.view(frame.to_local(wi));
    // f_r · cos⁺θ of a world direction, and the BRDF's sampling density.
    let reflect = |d: V3<f64>| {
        let wo = frame.to_local(d);
        scaled(view.eval(wo), wo[2].max(0.0))
    };
    let bsdf_sample = |rng: &mut Rng| {
        let s = view.sample([rng.next_float(), rng.next_float(), rng.next_float()]);
        (frame.to_world(s.wo), s)
    };
    let times = |a: V3<f64>, b: V3<f64>| [a[0] * b[0], a[1] * b[1], a[2] * b[2]];
    match plan.strategy {
        Strategy::Bsdf => plan.estimate(3, |rng| {
            let (d, s) = bsdf_sample(rng);
            times(s.weight, env.eval(d))
        }),
        Strategy::Emitter => plan.estimate(2, |rng| {
            let s = env.sample(next2(rng));
            times(s.weight, reflect(s.direction))
        }),
        Strategy::Mis => plan.estimate(5, |rng| {
            let (d, b) = bsdf_sample(rng);
            let w = heuristic.weight(b.pdf, env.pdf(d));
            let from_bsdf = scaled(times(b.weight, env.eval(d)), w);
            let s = env.sample(next2(rng));
            let w = heuristic.weight(s.pdf, view.pdf(frame.to_local(s.direction)));
            add(from_bsdf, scaled(times(s.weight, reflect(s.direction)), w))
        }),
        Strategy::Uniform | Strategy::Cosine => {
            Err(unsupported(plan.strategy, r#""bsdf", "emitter" or "mis""#))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envmap::Options;
    use crate::phong::Selection;

    fn plan(n: usize, strategy: Strategy, seed: u64) -> Plan {
        Plan {
            n,
            strategy,
            heuristic: Heuristic::Power,
            seed,
        }
    }

    fn sky() -> EnvMap {
        let (w, h) = (32, 17);
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = if (x, y) == (10, 5) {
                    200.0
                } else {
                    0.5 + y as f32 / 16.0
                };
                data.extend([v, 0.8 * v, 0.6 * v]);
            }
        }
        EnvMap::new(w, h, &data, Options::default()).unwrap()
    }

    fn z(a: &Estimate, b: &Estimate) -> f64 {
        (a.value[0] - b.value[0]) / a.stderr[0].hypot(b.stderr[0])
    }

    #[test]
    fn strategies_agree_and_mis_is_deterministic() {
        let env = sky();
        let normal = [0.3, 0.9, 0.1];
        let reference = irradiance(&env, normal, plan(400_000, Strategy::Emitter, 1)).unwrap();
        for strategy in [Strategy::Uniform, Strategy::Cosine, Strategy::Mis] {
            let e = irradiance(&env, normal, plan(400_000, strategy, 2)).unwrap();
            assert!(z(&e, &reference).abs() < 5.0, "{e:?} vs {reference:?}");
        }
        parallel::set_num_threads(1).unwrap();
        let one = irradiance(&env, normal, plan(100_000, Strategy::Mis, 3)).unwrap();
        parallel::set_num_threads(3).unwrap();
        let three = irradiance(&env, normal, plan(100_000, Strategy::Mis, 3)).unwrap();
        assert_eq!(one, three);
    }

    #[test]
    fn reflected_strategies_agree() {
        let env = sky();
        let phong = Phong::new([0.2; 3], [0.6; 3], 40.0, Selection::Max).unwrap();
        let (normal, wi) = ([0.0, 1.0, 0.0], [0.5, 0.8, 0.0]);
        let reference =
            reflected_radiance(&env, &phong, normal, wi, plan(400_000, Strategy::Mis, 1)).unwrap();
        for strategy in [Strategy::Bsdf, Strategy::Emitter] {
            let e =
                reflected_radiance(&env, &phong, normal, wi, plan(400_000, strategy, 2)).unwrap();
            assert!(z(&e, &reference).abs() < 5.0, "{e:?} vs {reference:?}");
        }
        let cosine = plan(10, Strategy::Cosine, 1);
        assert!(reflected_radiance(&env, &phong, normal, wi, cosine).is_err());
        assert!(irradiance(&env, [0.0; 3], cosine).is_err());
        assert!(irradiance(&env, normal, plan(0, Strategy::Cosine, 1)).is_err());
    }
}
