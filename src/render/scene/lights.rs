//! Emitter sampling: the lights of a scene, how one is chosen and
//! sampled, and the densities of those draws.

use glam::Vec3A;
use std::sync::Arc;

use super::{Environment, Scene};
use crate::distr::Discrete1D;
use crate::envmap::{CellSampler, EnvMap, EnvSample, EnvSamples};
use crate::render::accel::Primitive;
use crate::render::shape::{Ray, SurfacePoint};

/// Something emitter sampling can draw a direction toward.
#[derive(Clone, Debug)]
pub(super) enum Light {
    /// An area light.
    Area(AreaLight),
    /// The environment, by either density.
    Environment(EnvLight),
}

/// How emitter sampling chooses a light: in proportion to the lights'
/// powers `Φ_i`, with probability `P(i) = Φ_i / ΣΦ`.
#[derive(Clone, Debug)]
pub(super) struct LightChoice {
    table: Discrete1D,
    /// `P(i)` rounded to `f32`, as every density that includes the choice
    /// uses it.
    pmfs: Vec<f32>,
}

impl LightChoice {
    /// The choice among lights of `powers` (`None` without a light).
    ///
    /// # Errors
    /// As [`Discrete1D::new`].
    pub(super) fn new(powers: &[f64]) -> crate::error::Result<Option<Self>> {
        if powers.is_empty() {
            return Ok(None);
        }
        let table = Discrete1D::new(powers)?;
        let pmfs = (0..powers.len()).map(|i| table.pmf(i) as f32).collect();
        Ok(Some(LightChoice { table, pmfs }))
    }

    /// The light `u` chooses ([`Discrete1D::sample`]) and its `P(i)`.
    #[inline]
    fn sample(&self, u: f32) -> (usize, f32) {
        let i = self.table.sample(u);
        (i, self.pmf(i))
    }

    /// `P(i)` (0 outside the lights).
    #[inline]
    fn pmf(&self, i: usize) -> f32 {
        self.pmfs.get(i).copied().unwrap_or(0.0)
    }
}

/// The density emitter sampling draws the environment by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvDensity {
    /// The map's own (the one it was built with): for emitter sampling
    /// alone, light tracing and bidirectional path tracing, whose weights
    /// need every strategy's density. Unless the map was built
    /// compensated, it is positive wherever the map shines.
    Complete,
    /// For MIS with BSDF sampling (the direct and path integrators), a
    /// map's density with `compensate` ([`EnvMap::compensated`]: its
    /// luminance less the mean, clamped at 0; MIS compensation, Karlík et
    /// al. 2019, as pbrt-v4 samples its image lights under MIS): the dark
    /// parts are left to BSDF sampling, whose MIS weight is 1 there. A
    /// constant environment keeps its uniform density.
    Compensated,
}

/// The environment as a light: a way to draw it by each density.
#[derive(Clone, Debug)]
pub(in crate::render) struct EnvLight {
    complete: EnvDraw,
    compensated: Option<EnvDraw>,
}

/// One density of the environment: the environment drawn by it (a map's
/// own or its compensated twin, or a constant) and the map's
/// [`CellSampler`] where it has one.
#[derive(Clone, Debug)]
struct EnvDraw {
    env: Environment,
    cells: Option<CellSampler>,
}

impl EnvLight {
    /// The light of `env`; a map gets its compensated twin.
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the twin or a cell sampler cannot be
    /// had.
    pub(in crate::render) fn new(env: &Environment) -> crate::Result<Self> {
        let draw = |env: Environment| -> crate::Result<EnvDraw> {
            let cells = match &env {
                Environment::Map(map) => CellSampler::new(map)?,
                Environment::Constant(_) => None,
            };
            Ok(EnvDraw { env, cells })
        };
        let twin = match env {
            Environment::Map(map) => map.compensated()?,
            Environment::Constant(_) => None,
        };
        Ok(EnvLight {
            complete: draw(env.clone())?,
            compensated: twin
                .map(|m| draw(Environment::Map(Arc::new(m))))
                .transpose()?,
        })
    }

    /// The draw by `density` (the complete one where there is no twin).
    #[inline]
    fn draw(&self, density: EnvDensity) -> &EnvDraw {
        match (density, &self.compensated) {
            (EnvDensity::Compensated, Some(twin)) => twin,
            _ => &self.complete,
        }
    }
}

/// A light chosen for emitter sampling ([`Scene::choose_light`]), the
/// probability of that choice, and the density to draw the environment by
/// if it is chosen.
#[derive(Clone, Copy, Debug)]
pub struct ChosenLight<'a> {
    light: &'a Light,
    pmf: f32,
    density: EnvDensity,
}

impl ChosenLight<'_> {
    /// Whether the light is the environment.
    #[inline]
    pub fn is_environment(&self) -> bool {
        matches!(self.light, Light::Environment(_))
    }

    /// The environment map's cell sampler (of the density it was chosen
    /// for), when the light is a map that has one: its draws take 64
    /// random bits.
    #[inline]
    pub fn cells(&self) -> Option<&CellSampler> {
        match self.light {
            Light::Environment(light) => light.draw(self.density).cells.as_ref(),
            Light::Area(_) => None,
        }
    }
}

/// The emitting shape `shape`, whose primitives are
/// `primitives[first..first + count]`, one chosen by area (`areas`, when
/// there are several).
#[derive(Clone, Debug)]
pub(super) struct AreaLight {
    pub(super) shape: u32,
    pub(super) first: u32,
    pub(super) count: u32,
    pub(super) areas: Option<Discrete1D>,
    pub(super) total_area: f32,
    pub(super) radiance: [f32; 3],
}

/// A direction toward a light, from emitter sampling.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point toward the light.
    pub d: Vec3A,
    /// Distance to the light point (infinite for the environment).
    pub dist: f32,
    /// Density per steradian, including the choice of the light.
    pub pdf: f32,
    /// Radiance arriving along `d` (before the visibility test).
    pub radiance: [f32; 3],
    /// The point on an area light (where the shadow ray ends) and its
    /// shape, `None` for the environment.
    pub point: Option<(SurfacePoint, u32)>,
}

impl LightSample {
    /// The point on an area light where the shadow ray ends (`None` for
    /// the environment).
    #[inline]
    pub fn end(&self) -> Option<&SurfacePoint> {
        self.point.as_ref().map(|(y, _)| y)
    }
}

/// Where light starts ([`Scene::sample_emission`]).
#[derive(Clone, Copy, Debug)]
pub enum Emission {
    /// A point on an area light.
    Surface {
        /// The shape it lies on.
        shape: u32,
        /// The point (light leaves its front side, along `ng`).
        point: SurfacePoint,
        /// Density per unit area, including the choice of the light.
        pdf: f32,
        /// Emitted radiance.
        radiance: [f32; 3],
    },
    /// Light from the environment.
    Environment {
        /// Unit direction toward the environment (light travels along `−d`).
        d: Vec3A,
        /// Density per steradian, including the choice of the light.
        pdf: f32,
        /// Radiance arriving along `−d`.
        radiance: [f32; 3],
        /// The probability of having chosen the environment.
        choice: f32,
    },
}

impl Scene {
    fn choice_pmf(&self, light: Option<u32>) -> f32 {
        match (light, &self.light_choice) {
            (Some(l), Some(choice)) => choice.pmf(l as usize),
            _ => 0.0,
        }
    }

    /// Density per steradian with which emitter sampling from the shading
    /// point `x` draws the direction `d` that reaches shape `shape` at
    /// distance `dist`, where its geometric normal is `ng`: the choice of
    /// the light times [`Sphere::cone_pdf`](crate::render::shape::Sphere::cone_pdf) for a sphere seen from outside,
    /// else `dist² / (|cos θ_light| A)` (uniform by area `A`, turned into
    /// solid angle).
    #[inline]
    pub fn light_pdf(&self, shape: u32, x: Vec3A, ng: Vec3A, d: Vec3A, dist: f32) -> f32 {
        let light = self.light_of_shape[shape as usize];
        let Some(Light::Area(area)) = light.map(|l| &self.lights[l as usize]) else {
            return 0.0;
        };
        let pmf = self.choice_pmf(light);
        if let Primitive::Sphere(s) = &self.accel.primitives()[area.first as usize]
            && let Some(pdf) = s.cone_pdf(x)
        {
            return pmf * pdf;
        }
        let cos = ng.dot(d).abs();
        if cos <= 0.0 {
            return 0.0;
        }
        pmf * dist * dist / (cos * area.total_area)
    }

    /// The density per unit area with which [`Scene::sample_emission`]
    /// draws a point of shape `shape` (0 unless it is an area light): the
    /// choice of its light over its area.
    pub fn emission_pdf(&self, shape: u32) -> f32 {
        let light = self.light_of_shape[shape as usize];
        match light.map(|l| &self.lights[l as usize]) {
            Some(Light::Area(area)) => self.choice_pmf(light) / area.total_area,
            _ => 0.0,
        }
    }

    /// The density per steradian with which [`Scene::sample_light`] and
    /// [`Scene::sample_emission`] draw the environment direction `d` (the
    /// choice of the environment included).
    pub fn environment_pdf(&self, d: Vec3A) -> f32 {
        self.environment
            .as_ref()
            .map_or(0.0, |env| self.choice_pmf(self.env_light) * env.pdf(d))
    }

    /// `out[i]`: the density per steradian with which emitter sampling by
    /// `density` draws the environment direction `d[i]` (the choice of the
    /// environment among the lights included).
    pub fn environment_pdf_into(&self, d: &[[f32; 3]], out: &mut [f32], density: EnvDensity) {
        let pmf = self.choice_pmf(self.env_light);
        match self.env_draw(density).map(|draw| &draw.env) {
            Some(Environment::Map(env)) => {
                env.pdf_into(d, out, |_| true);
                out.iter_mut().for_each(|p| *p *= pmf);
            }
            Some(env) => out.fill(pmf * env.pdf(Vec3A::Z)),
            None => out.fill(0.0),
        }
    }

    /// The environment light's draw by `density`, when it is a light.
    fn env_draw(&self, density: EnvDensity) -> Option<&EnvDraw> {
        match self.lights.get(self.env_light? as usize)? {
            Light::Environment(light) => Some(light.draw(density)),
            Light::Area(_) => None,
        }
    }

    /// The density per steradian with which [`Scene::sample_light`] from
    /// `x` draws the unit direction `d`: over the lights, the probability of
    /// choosing each times its density toward `d`. An area light counts
    /// where `d` first meets it (among its own primitives: other shapes are
    /// ignored, as the sampler ignores them) on its front side.
    pub fn emitter_pdf(&self, x: Vec3A, d: Vec3A) -> f32 {
        let ray = Ray {
            o: x,
            d,
            tmax: f32::INFINITY,
        };
        let mut pdf = 0.0;
        for (index, light) in self.lights.iter().enumerate() {
            match light {
                Light::Area(AreaLight {
                    shape,
                    first,
                    count,
                    ..
                }) => {
                    let own = &self.accel.primitives()[*first as usize..(first + count) as usize];
                    let nearest = own
                        .iter()
                        .filter_map(|p| p.intersect(&ray, self.accel.meshes()).map(|c| (p, c)))
                        .min_by(|a, b| a.1.t.total_cmp(&b.1.t));
                    if let Some((p, c)) = nearest {
                        let y = p.point(x + d * c.t, c.bary, self.accel.meshes());
                        if self.emitted(*shape, y.ng, -d).is_some() {
                            pdf += self.light_pdf(*shape, x, y.ng, d, c.t);
                        }
                    }
                }
                Light::Environment(_) => {
                    if let Some(env) = &self.environment {
                        pdf += self.choice_pmf(Some(index as u32)) * env.pdf(d);
                    }
                }
            }
        }
        pdf
    }

    /// A primitive of `area` chosen by area with `u[0]`, and `u` made
    /// uniform again.
    #[inline]
    fn pick_primitive(&self, area: &AreaLight, u: [f32; 2]) -> (&Primitive, [f32; 2]) {
        let (k, u0) = match &area.areas {
            Some(a) => a.sample_reuse(u[0]),
            None => (0, u[0]),
        };
        (
            &self.accel.primitives()[area.first as usize + k],
            [u0, u[1]],
        )
    }

    /// Where light starts, for light tracing: a light chosen by power
    /// (`u[0]`, as [`Scene::sample_light`]), then a point on an area light
    /// uniformly by area, or a direction toward the environment by its own
    /// sampling ([`Environment::sample`] by inversion) (`u[1..3]`). `None`
    /// when the scene has no light or the sample carries no radiance.
    pub fn sample_emission(&self, u: [f32; 3]) -> Option<Emission> {
        let (index, pmf) = self.light_choice.as_ref()?.sample(u[0]);
        match &self.lights[index] {
            Light::Environment(_) => {
                let (d, pdf, radiance) = self.environment.as_ref()?.sample([u[1], u[2]], None);
                (pdf > 0.0).then_some(Emission::Environment {
                    d,
                    pdf: pdf * pmf,
                    radiance,
                    choice: pmf,
                })
            }
            Light::Area(area) => {
                let (primitive, u2) = self.pick_primitive(area, [u[1], u[2]]);
                Some(Emission::Surface {
                    shape: area.shape,
                    point: primitive.sample(u2, self.accel.meshes()),
                    pdf: pmf / area.total_area,
                    radiance: area.radiance,
                })
            }
        }
    }

    /// Emitter sampling from the shading point `x`: a light chosen by power
    /// (`u[0]`, [`Scene::choose_light`]), then a point on it (uniformly by
    /// area, or for a sphere seen from outside by the cone it subtends) or
    /// an environment direction by the environment's own sampling
    /// (`u[1..3]`; a map's cell by its [`CellSampler`] from 64 bits of
    /// `bits` when given, else by
    /// [`EnvMap::sample`](crate::envmap::EnvMap::sample) of `u[1..3]`, with
    /// the same density), by the complete density ([`EnvDensity::Complete`]).
    /// `None` when the scene has no light or the sample carries no
    /// radiance.
    #[inline]
    pub fn sample_light(
        &self,
        x: Vec3A,
        u: [f32; 3],
        bits: Option<impl FnOnce() -> u64>,
    ) -> Option<LightSample> {
        let light = self.choose_light(u[0], EnvDensity::Complete)?;
        let bits = light.cells().and(bits).map(|bits| bits());
        self.sample_chosen(light, x, [u[1], u[2]], bits)
    }

    /// [`Scene::sample_chosen`] of the environment by `draw`, chosen with
    /// probability `pmf`: by its map's cell sampler and the 64 random
    /// `bits` when both are there, else by inversion of `u`.
    #[inline]
    fn sample_environment(
        draw: &EnvDraw,
        pmf: f32,
        u: [f32; 2],
        bits: Option<u64>,
    ) -> Option<LightSample> {
        let (d, pdf, radiance) = draw.env.sample(u, draw.cells.as_ref().zip(bits));
        environment_sample(d, pdf, pmf, radiance)
    }

    /// The environment drawn by `density` (by that density's cell sampler,
    /// [`ChosenLight::cells`]) for each `(bits, u)` of `draws`: the
    /// samples [`Scene::sample_chosen`] draws one at a time, drawn
    /// together ([`CellSampler::sample_many`]) and handed to `put` with
    /// their draw's index (`scratch`: the map's samples); nothing without
    /// a cell sampler.
    pub fn sample_environment_cells(
        &self,
        draws: &[(u64, [f32; 2])],
        scratch: &mut Vec<EnvSample<f32>>,
        density: EnvDensity,
        mut put: impl FnMut(usize, Option<LightSample>),
    ) {
        let Some(EnvDraw {
            env: Environment::Map(env),
            cells: Some(cells),
        }) = self.env_draw(density)
        else {
            return;
        };
        let pmf = self.choice_pmf(self.env_light);
        scratch.clear();
        cells.sample_many(env, draws, scratch);
        debug_assert_eq!(scratch.len(), draws.len());
        for (i, s) in scratch.iter().enumerate() {
            put(
                i,
                environment_sample(Vec3A::from(s.direction), s.pdf, pmf, s.radiance),
            );
        }
    }

    /// The environment drawn by `density`, by inversion (no cells), for
    /// each `u` of `us`: the samples [`Scene::sample_chosen`] draws one at
    /// a time, drawn together ([`EnvMap::sample_into`], in `f64` as one
    /// draw is) and handed to `put` with their draw's index (`scratch`: the
    /// map's samples); nothing when the environment is not a map.
    pub fn sample_environment_inverted(
        &self,
        us: &[[f64; 2]],
        scratch: &mut InvertedSamples,
        density: EnvDensity,
        mut put: impl FnMut(usize, Option<LightSample>),
    ) {
        let Some(EnvDraw {
            env: Environment::Map(env),
            ..
        }) = self.env_draw(density)
        else {
            return;
        };
        let pmf = self.choice_pmf(self.env_light);
        let InvertedSamples {
            direction,
            pdf,
            weight,
        } = scratch;
        for v in [&mut *direction, &mut *weight] {
            v.clear();
            v.resize(us.len(), [0.0; 3]);
        }
        pdf.clear();
        pdf.resize(us.len(), 0.0);
        let samples = EnvSamples {
            direction,
            pdf,
            weight,
        };
        env.sample_into(us, samples);
        for i in 0..us.len() {
            let s = EnvSample {
                direction: direction[i],
                pdf: pdf[i],
                weight: weight[i],
                radiance: [0.0; 3],
            };
            let (d, pdf, radiance) = Environment::of_inversion(s);
            put(i, environment_sample(d, pdf, pmf, radiance));
        }
    }

    /// The environment map, when the scene's environment is one.
    pub fn environment_map(&self) -> Option<&EnvMap> {
        match &self.environment {
            Some(Environment::Map(env)) => Some(env),
            _ => None,
        }
    }

    /// Whether the scene has more than one light, so that
    /// [`Scene::choose_light`] reads its number.
    #[inline]
    pub fn chooses_among_lights(&self) -> bool {
        self.lights.len() > 1
    }

    /// The light emitter sampling draws by `u` (by power), to be sampled
    /// by `density` if it is the environment, or `None` when the scene has
    /// none.
    #[inline]
    pub fn choose_light(&self, u: f32, density: EnvDensity) -> Option<ChosenLight<'_>> {
        let (index, pmf) = self.light_choice.as_ref()?.sample(u);
        Some(ChosenLight {
            light: &self.lights[index],
            pmf,
            density,
        })
    }

    /// [`Scene::sample_light`] of the chosen `light` (the environment by
    /// the density it was chosen for), with `u` the position's numbers and
    /// `bits` the [`CellSampler`]'s (used only when [`ChosenLight::cells`]
    /// has one).
    #[inline]
    pub fn sample_chosen(
        &self,
        ChosenLight {
            light,
            pmf,
            density,
        }: ChosenLight<'_>,
        x: Vec3A,
        u: [f32; 2],
        bits: Option<u64>,
    ) -> Option<LightSample> {
        match light {
            Light::Environment(env) => Self::sample_environment(env.draw(density), pmf, u, bits),
            Light::Area(area) => {
                let (primitive, u2) = self.pick_primitive(area, u);
                // A sphere seen from outside: by the cone it subtends.
                let (y, cone_pdf) = match primitive {
                    Primitive::Sphere(s) => match s.sample_cone(x, u2) {
                        Some((y, pdf)) => (y, Some(pdf)),
                        None => (s.sample(u2), None),
                    },
                    _ => (primitive.sample(u2, self.accel.meshes()), None),
                };
                let to_light = y.p - x;
                let dist = to_light.length();
                if dist <= 0.0 {
                    return None;
                }
                let d = to_light / dist;
                let cos = -y.ng.dot(d);
                let pdf = cone_pdf.unwrap_or(dist * dist / (cos * area.total_area));
                (cos > 0.0 && pdf.is_finite()).then_some(LightSample {
                    d,
                    dist,
                    pdf: pmf * pdf,
                    radiance: area.radiance,
                    point: Some((y, area.shape)),
                })
            }
        }
    }
}

/// The light sample toward the environment along `d`, drawn with density
/// `pdf` by the environment, chosen with probability `pmf`; `None` where
/// `pdf` is 0.
#[inline(always)]
fn environment_sample(d: Vec3A, pdf: f32, pmf: f32, radiance: [f32; 3]) -> Option<LightSample> {
    (pdf > 0.0).then_some(LightSample {
        d,
        dist: f32::INFINITY,
        pdf: pdf * pmf,
        radiance,
        point: None,
    })
}

/// Scratch for [`Scene::sample_environment_inverted`]: the map's samples.
#[derive(Debug, Default)]
pub struct InvertedSamples {
    direction: Vec<[f64; 3]>,
    pdf: Vec<f64>,
    weight: Vec<[f64; 3]>,
}
