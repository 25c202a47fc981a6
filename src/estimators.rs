//! Monte Carlo estimators of the light an environment map delivers to a
//! point: irradiance on a surface, and radiance reflected by a Phong
//! surface, each by several sampling strategies and their MIS combination.
//!
//! An estimate averages `n` evaluations `f_i`; its standard error is
//! `s/√n` with `s²` the sample variance. Sample `i` takes its uniform
//! numbers from dimensions `0, 1, 2, …` of sample `i` of one [`Stream`] of
//! the plan's [`Sampler`], as the formulas below number them (a BRDF sample:
//! its lobe dimension 0, its direction the pair 1–2, drawn first; under the
//! independent sampler the draws' order is their meaning: the PCG32 stream
//! of `seed` advanced to `i · draws`), so the result is the same bits
//! whatever the thread count.
//! With a stratified or low-discrepancy sampler the `f_i` are no longer
//! independent, and `s/√n` usually overstates the error (it is the error of
//! independent sampling): compare seeds to measure it.
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

use crate::alloc;
use crate::envmap::EnvMap;
use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::math::{V3, dot};
use crate::mis::Heuristic;
use crate::parallel;
use crate::phong::Phong;
use crate::qmc::patterns::mix64;
use crate::rng::Rng;
use crate::sampler::zorder::ZOrder;
use crate::sampler::{Sampler, Stream};
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
/// `heuristic`), random numbers from `sampler` seeded by `seed`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    /// Number of evaluations, at least 1.
    pub n: usize,
    /// The sampling strategy.
    pub strategy: Strategy,
    /// The MIS heuristic (for [`Strategy::Mis`]).
    pub heuristic: Heuristic,
    /// Seed of the PCG32 stream, or of the scrambles and patterns.
    pub seed: u64,
    /// Where the numbers come from.
    pub sampler: Sampler,
    /// The index of the first evaluation in the sequence: a chunk of a
    /// longer run ([`merge`]). A multiple of [`PART`].
    pub first: usize,
    /// The sequence's length (at least `first + n`), which the samplers
    /// other than the independent one lay their patterns over.
    pub total: usize,
    /// Whether the estimate keeps its [`Part`]s, for [`merge`].
    pub keep_parts: bool,
}

/// Evaluations per partial sum: an estimate is the ordered merge of the
/// moments of its blocks of `PART` evaluations (whatever the thread
/// count), and a chunk of a run must start at a multiple of it.
pub const PART: usize = parallel::CHUNK;

/// The moments of the evaluations `start .. start + n` of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part {
    /// Index of the first evaluation.
    pub start: usize,
    /// Number of evaluations (`PART`, or fewer for a run's last part).
    pub n: usize,
    /// Their mean.
    pub mean: V3<f64>,
    /// Their sum of squared deviations from the mean.
    pub m2: V3<f64>,
}

/// A Monte Carlo estimate of an RGB quantity.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The mean of the evaluations.
    pub value: V3<f64>,
    /// Its standard error, `s/√n`.
    pub stderr: V3<f64>,
    /// The number of evaluations.
    pub n: usize,
    /// The moments of its blocks of [`PART`] evaluations, in order, when
    /// [`Plan::keep_parts`] asked for them (else empty).
    pub parts: Vec<Part>,
}

impl Estimate {
    /// The estimate of `parts` (in order, following one another): their
    /// moments merged one after another, from the first.
    ///
    /// # Errors
    /// [`Error::Argument`] when there are none or they do not follow one
    /// another.
    pub fn from_parts(parts: Vec<Part>, keep_parts: bool) -> Result<Estimate> {
        let not_following = parts.windows(2).find(|w| w[0].start + w[0].n != w[1].start);
        if let Some(w) = not_following {
            return Err(Error::Argument {
                arg: "estimates",
                message: format!(
                    "the chunks do not follow one another: evaluations {} .. {} are followed \
                     by evaluations from {}",
                    w[0].start,
                    w[0].start + w[0].n,
                    w[1].start
                ),
            });
        }
        if parts.is_empty() {
            return Err(Error::Argument {
                arg: "estimates",
                message: "estimates hold no evaluations: nothing to merge".into(),
            });
        }
        let m = parts.iter().fold(Moments::default(), |acc, p| {
            acc.merge(Moments {
                n: p.n as f64,
                mean: p.mean,
                m2: p.m2,
            })
        });
        let n = parts.iter().map(|p| p.n).sum();
        let stderr = if n > 1 {
            m.m2.map(|v| (v / (m.n - 1.0) / m.n).sqrt())
        } else {
            [f64::INFINITY; 3]
        };
        Ok(Estimate {
            value: m.mean,
            stderr,
            n,
            parts: if keep_parts { parts } else { Vec::new() },
        })
    }
}

/// Chunks of one run merged (their parts in order of their first
/// evaluation): the bits of one run of all their evaluations.
///
/// # Errors
/// As [`Estimate::from_parts`].
pub fn merge(chunks: &[&Estimate]) -> Result<Estimate> {
    let mut parts: Vec<Part> = alloc::with_capacity(
        chunks.iter().map(|c| c.parts.len()).sum(),
        "the partial sums",
    )?;
    for c in chunks {
        parts.extend_from_slice(&c.parts);
    }
    parts.sort_by_key(|p| p.start);
    Estimate::from_parts(parts, true)
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
    /// The mean and standard error of `f(stream)` over `n` evaluations, the
    /// stream at sample `i` for evaluation `i` (which draws `draws`
    /// independent numbers).
    ///
    /// # Errors
    /// [`Error::Integer`] for `n = 0`, or `n` above the sampler's
    /// [`Sampler::max_count`]; [`Error::Memory`].
    fn estimate(self, draws: u64, f: impl Fn(&mut Stream) -> V3<f64> + Sync) -> Result<Estimate> {
        let Plan { n, seed, first, .. } = self;
        self.sampler.check_count("n", self.total as u64)?;
        if n == 0 {
            return Err(Error::Integer {
                arg: "n",
                value: "0".into(),
                requirement: "must be at least 1".into(),
            });
        }
        if !first.is_multiple_of(PART) || first.saturating_add(n) > self.total {
            return Err(Error::Integer {
                arg: "first_sample",
                value: first.to_string(),
                requirement: format!(
                    "must be a multiple of {PART} (the evaluations of a partial sum), with \
                     first_sample + n at most the sequence's length ({})",
                    self.total
                ),
            });
        }
        let base = Stream::new(
            self.sampler,
            mix64(seed),
            Rng::new(seed, 0),
            self.total as u64,
            ZOrder::new((0, 0), (1, 1), self.total as u64, seed),
        );
        // One partial sum per block of PART evaluations, reserved up front
        // (2^26 of them for the largest n): too many for memory is an
        // error before any work.
        let parts = Mutex::new(alloc::with_capacity(n.div_ceil(PART), "the partial sums")?);
        parallel::for_each_chunk(n, (), |range, ()| {
            // Blocks of PART evaluations, whatever the range a thread is
            // handed: the same sums in the same order on any pool. The
            // evaluation at index i draws from i·draws on (positional, so
            // that a chunk of a run draws what the whole run draws).
            let mut local = Vec::new();
            for offset in range.clone().step_by(PART) {
                let start = first + offset;
                let mut stream = base.jumped(start as u64 * draws);
                let mut m = Moments::default();
                for i in start..start + PART.min(range.end - offset) {
                    stream.start(i as u32);
                    m.push(f(&mut stream));
                }
                local.push(Part {
                    start,
                    n: m.n as usize,
                    mean: m.mean,
                    m2: m.m2,
                });
            }
            parts
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .extend(local);
            true
        })?;
        let mut parts = parts.into_inner().unwrap_or_else(|p| p.into_inner());
        parts.sort_by_key(|p| p.start);
        Estimate::from_parts(parts, self.keep_parts)
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
        Strategy::Uniform => plan.estimate(2, |s| {
            let d = frame.to_world(warp::square_to_uniform_hemisphere(s.get2(0)));
            scaled(env.eval(d), dot(d, normal).max(0.0) * 2.0 * PI)
        }),
        Strategy::Cosine => plan.estimate(2, |s| {
            let local = warp::square_to_cosine_hemisphere(s.get2(0));
            let f = if local[2] > 0.0 { PI } else { 0.0 };
            scaled(env.eval(frame.to_world(local)), f)
        }),
        Strategy::Emitter => plan.estimate(2, |s| {
            let s = env.sample(s.get2(0));
            scaled(s.weight, dot(s.direction, normal).max(0.0))
        }),
        Strategy::Mis => plan.estimate(4, |stream| {
            let d = frame.to_world(warp::square_to_cosine_hemisphere(stream.get2(0)));
            let p = cosine_pdf(d);
            let from_cosine = if p > 0.0 {
                let w = heuristic.weight(p, env.pdf(d));
                scaled(env.eval(d), w * dot(d, normal) / p)
            } else {
                [0.0; 3]
            };
            let s = env.sample(stream.get2(2));
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
    let bsdf_sample = |stream: &mut Stream| {
        let [u1, u2] = stream.get2(1);
        let lobe = stream.get1(0);
        let s = view.sample([u1, u2, lobe]);
        (frame.to_world(s.wo), s)
    };
    let times = |a: V3<f64>, b: V3<f64>| [a[0] * b[0], a[1] * b[1], a[2] * b[2]];
    match plan.strategy {
        Strategy::Bsdf => plan.estimate(3, |stream| {
            let (d, s) = bsdf_sample(stream);
            times(s.weight, env.eval(d))
        }),
        Strategy::Emitter => plan.estimate(2, |stream| {
            let s = env.sample(stream.get2(0));
            times(s.weight, reflect(s.direction))
        }),
        Strategy::Mis => plan.estimate(5, |stream| {
            let (d, b) = bsdf_sample(stream);
            let w = heuristic.weight(b.pdf, env.pdf(d));
            let from_bsdf = scaled(times(b.weight, env.eval(d)), w);
            let s = env.sample(stream.get2(3));
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
            sampler: Sampler::Independent,
            first: 0,
            total: n,
            keep_parts: false,
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
