//! A scene: shapes with their materials and emission, an optional
//! environment, the camera and the film size; and its lights, chosen by
//! power for emitter sampling.

use glam::Vec3A;

use super::accel::Hit;
use super::accel::{Accel, Primitive};
use super::camera::Camera;
pub use super::environment::Environment;
use super::filter::{FilmFilter, Filter};
use super::geometry::check_primitives;
pub use super::geometry::{Geometry, MAX_PRIMITIVES, affine, daffine};
use super::motion::{Motion, Mover};
use super::shape::{Ray, SurfacePoint};
use crate::alloc;
use crate::distr::Discrete1D;
use crate::envmap::CellSampler;
use crate::error::{Error, Result};
use crate::math::luminance;
use crate::phong::Phong;

/// A surface's BSDF: the Phong BRDF (a diffuse material is Phong with
/// `ρs = 0`), reflecting on the front side only unless `two_sided`, as in
/// Mitsuba (seen from the back, a one-sided material is black).
#[derive(Clone, Copy, Debug)]
pub struct Material {
    /// The BRDF.
    pub bsdf: Phong,
    /// Whether the back side reflects like the front.
    pub two_sided: bool,
}

/// A shape: geometry, material and, for an area light, its radiance (RGB,
/// emitted from the front side only, constant over the surface).
#[derive(Clone, Debug)]
pub struct Shape {
    /// Where it is.
    pub geometry: Geometry,
    /// How it reflects.
    pub material: Material,
    /// Emitted radiance, for an area light.
    pub emission: Option<[f64; 3]>,
    /// How it moves during the shutter, `geometry` being where it is at
    /// `shutter_open` (`to_world` there, `to_world_end` at `shutter_close`).
    pub motion: Option<Motion>,
}

/// Something emitter sampling can draw a direction toward.
#[derive(Clone, Debug)]
enum Light {
    /// An area light.
    Area(AreaLight),
    /// The environment, drawn by its map's [`CellSampler`] where it has
    /// one.
    Environment { cells: Option<CellSampler> },
}

/// The emitting shape `shape`, whose primitives are
/// `primitives[first..first + count]`, one chosen by area (`areas`, when
/// there are several).
#[derive(Clone, Debug)]
struct AreaLight {
    shape: u32,
    first: u32,
    count: u32,
    areas: Option<Discrete1D>,
    total_area: f32,
    radiance: [f32; 3],
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

/// The sphere of [`Scene::bounding_sphere`]: around the box that holds
/// the still shapes' box and the moving shapes' spheres.
fn bounding_sphere(accel: &Accel, movers: &[Mover]) -> (Vec3A, f32) {
    let moving = movers
        .iter()
        .filter_map(Mover::bounding_sphere)
        .map(|(c, r)| (c - Vec3A::splat(r), c + Vec3A::splat(r)));
    match accel
        .bounds()
        .into_iter()
        .chain(moving)
        .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    {
        Some((lo, hi)) => (0.5 * (lo + hi), 0.5 * (hi - lo).length()),
        None => (Vec3A::ZERO, 1.0),
    }
}

/// A scene ready to render.
pub struct Scene {
    accel: Accel,
    materials: Vec<Material>,
    emission: Vec<Option<[f32; 3]>>,
    light_of_shape: Vec<Option<u32>>,
    environment: Option<Environment>,
    env_light: Option<u32>,
    lights: Vec<Light>,
    light_choice: Option<Discrete1D>,
    camera: Camera,
    width: usize,
    height: usize,
    filter: FilmFilter,
    movers: Vec<Mover>,
    bounding_sphere: (Vec3A, f32),
}

impl Scene {
    /// Builds the BVH and the light selection (by power: `π A Y(L)` for an
    /// area light, `π R² ∫ Y(L) dω` for the environment, R the radius of
    /// [`Scene::bounding_sphere`]: the choice need not follow the powers
    /// exactly).
    ///
    /// # Errors
    /// [`Error::Parameter`] for a film of zero pixels.
    pub fn new(
        shapes: Vec<Shape>,
        environment: Option<Environment>,
        camera: Camera,
        width: usize,
        height: usize,
    ) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::Parameter {
                arg: "film",
                value: (width * height) as f64,
                requirement: "width and height must be >= 1",
            });
        }
        let count: usize = shapes.iter().map(|s| s.geometry.primitive_count()).sum();
        check_primitives("shapes", count)?;
        let mut primitives = alloc::with_capacity(count, "the scene's primitives")?;
        let mut shape_of = alloc::with_capacity(count, "the scene's primitives")?;
        let mut normals = Vec::new();
        let mut materials = Vec::with_capacity(shapes.len());
        let mut emission = Vec::with_capacity(shapes.len());
        let mut light_of_shape = Vec::with_capacity(shapes.len());
        let mut lights = Vec::new();
        let mut powers = Vec::new();
        let mut movers = Vec::new();
        for (index, shape) in shapes.into_iter().enumerate() {
            let id = index as u32;
            if let Some(motion) = shape.motion {
                if shape.emission.is_some() {
                    return Err(Error::Argument {
                        arg: "to_world_end",
                        message: format!(
                            "shape {index}: a moving area light is not supported (only \
                             shapes that do not emit may move)"
                        ),
                    });
                }
                let mut own_normals = Vec::new();
                let own = alloc::collect(
                    shape.geometry.into_primitives(&mut own_normals)?,
                    "a moving shape's primitives",
                )?;
                let shapes = alloc::collect(own.iter().map(|_| id), "a moving shape's primitives")?;
                movers.push(Mover::new(Accel::new(own, shapes, own_normals)?, motion));
                materials.push(shape.material);
                emission.push(None);
                light_of_shape.push(None);
                continue;
            }
            let first = primitives.len() as u32;
            primitives.extend(shape.geometry.into_primitives(&mut normals)?);
            shape_of.resize(primitives.len(), id);
            let areas = alloc::collect(
                primitives[first as usize..].iter().map(Primitive::area),
                "the areas",
            )?;
            materials.push(shape.material);
            let radiance = shape.emission.map(|l| l.map(|v| v as f32));
            emission.push(radiance);
            let total: f64 = areas.iter().sum();
            let power = shape
                .emission
                .map_or(0.0, |l| std::f64::consts::PI * total * luminance(l));
            if power > 0.0 {
                light_of_shape.push(Some(lights.len() as u32));
                lights.push(Light::Area(AreaLight {
                    shape: id,
                    first,
                    count: areas.len() as u32,
                    areas: (areas.len() > 1)
                        .then(|| Discrete1D::new(&areas))
                        .transpose()?,
                    total_area: total as f32,
                    radiance: radiance.unwrap_or_default(),
                }));
                powers.push(power);
            } else {
                light_of_shape.push(None);
            }
        }
        let accel = Accel::new(primitives, shape_of, normals)?;
        // At most MAX_PRIMITIVES in all (check_primitives above).
        let mut first = accel.primitives().len() as u32;
        for mover in &mut movers {
            first = mover.number_from(first);
        }
        let bounding_sphere = bounding_sphere(&accel, &movers);
        let radius = f64::from(bounding_sphere.1);
        let mut env_light = None;
        if let Some(env) = &environment {
            let power = std::f64::consts::PI * radius * radius * env.luminance_integral();
            if power > 0.0 {
                env_light = Some(lights.len() as u32);
                let cells = match env {
                    Environment::Map(map) => CellSampler::new(map)?,
                    Environment::Constant(_) => None,
                };
                lights.push(Light::Environment { cells });
                powers.push(power);
            }
        }
        let light_choice = (!powers.is_empty())
            .then(|| Discrete1D::new(&powers))
            .transpose()?;
        Ok(Scene {
            accel,
            materials,
            emission,
            light_of_shape,
            environment,
            env_light,
            lights,
            light_choice,
            camera,
            width,
            height,
            filter: FilmFilter::none(),
            movers,
            bounding_sphere,
        })
    }

    /// Whether anything moves during the shutter (a shape or the camera):
    /// samples then draw a time.
    pub fn moves(&self) -> bool {
        !self.movers.is_empty() || self.camera.moves()
    }

    /// The nearest hit of `ray` at time `tau` (of the shutter, in
    /// `[0, 1]`): in the BVH of the shapes that stay, then in each moving
    /// shape's own, placed where it is at `tau`.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, tau: f32) -> Option<Hit> {
        let best = self.accel.intersect(ray);
        if self.movers.is_empty() {
            best
        } else {
            self.intersect_movers(ray, tau, best)
        }
    }

    /// [`Scene::intersect`] among the moving shapes, given the `best` hit
    /// so far (`best` when nothing moves).
    #[inline(never)]
    pub fn intersect_movers(&self, ray: &Ray, tau: f32, best: Option<Hit>) -> Option<Hit> {
        self.movers
            .iter()
            .fold(best, |best, m| m.intersect(ray, tau, best))
    }

    /// Whether anything lies on `ray` in `(0, ray.tmax)` at time `tau`.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, tau: f32) -> bool {
        self.accel.occluded(ray) || (!self.movers.is_empty() && self.movers_occlude(ray, tau))
    }

    /// Whether a moving shape lies on `ray` at time `tau`.
    #[inline(never)]
    pub fn movers_occlude(&self, ray: &Ray, tau: f32) -> bool {
        self.movers.iter().any(|m| m.occludes(ray, tau))
    }

    /// The shape `ray` meets at `hit` (found by [`Scene::intersect`] at
    /// time `tau`) and the surface point there; a moving shape's normals
    /// are carried by the inverse transpose of its motion.
    #[inline(always)]
    pub fn surface(&self, ray: &Ray, hit: &Hit, tau: f32) -> (u32, SurfacePoint) {
        if hit.primitive as usize >= self.accel.primitives().len() {
            return self.moving_surface(ray, hit, tau);
        }
        let primitive = &self.accel.primitives()[hit.primitive as usize];
        (
            self.accel.shape_of(hit.primitive),
            primitive.point(ray.o + ray.d * hit.t, hit.bary, self.accel.normals()),
        )
    }

    /// [`Scene::surface`] of a hit on a moving shape.
    #[inline(never)]
    fn moving_surface(&self, ray: &Ray, hit: &Hit, tau: f32) -> (u32, SurfacePoint) {
        let k = self.movers.partition_point(|m| m.first() <= hit.primitive) - 1;
        self.movers[k].surface(ray, hit, tau)
    }

    /// The scene with the film's reconstruction `filter` (the box filter
    /// unless set), sampled on the film or, with `sample_border`, on the
    /// film grown by the filter's border.
    ///
    /// # Errors
    /// As [`FilmFilter::new`].
    pub fn with_filter(self, filter: Filter, sample_border: bool) -> Result<Self> {
        let filter = FilmFilter::new(filter, self.film(), sample_border)?;
        Ok(Scene { filter, ..self })
    }

    /// The film's reconstruction filter.
    pub fn filter(&self) -> &FilmFilter {
        &self.filter
    }

    /// The film size `(width, height)` in pixels.
    pub fn film(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The BVH of the shapes that do not move (the moving shapes have
    /// their own: [`Scene::intersect`] traces both).
    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    /// What traces the scene's triangles: `"embree 3.13.5"` when Embree
    /// traces any of them (see [`super::embree`]), otherwise `"obvhs"`.
    pub fn ray_tracer(&self) -> String {
        std::iter::once(&self.accel)
            .chain(self.movers.iter().map(Mover::accel))
            .map(Accel::ray_tracer)
            .find(|name| name != super::accel::OBVHS)
            .unwrap_or_else(|| super::accel::OBVHS.into())
    }

    /// The material of shape `shape`.
    #[inline]
    pub fn material(&self, shape: u32) -> &Material {
        &self.materials[shape as usize]
    }

    /// The environment, if any.
    pub fn environment(&self) -> Option<&Environment> {
        self.environment.as_ref()
    }

    /// Whether shape `shape` is an area light.
    #[inline]
    pub fn is_emitter(&self, shape: u32) -> bool {
        self.emission[shape as usize].is_some()
    }

    /// Radiance emitted by shape `shape` at a point with geometric normal
    /// `ng` toward `w` (unit, away from the surface): its radiance on the
    /// front side, 0 behind it or for a shape that does not emit.
    #[inline]
    pub fn emitted(&self, shape: u32, ng: Vec3A, w: Vec3A) -> Option<[f32; 3]> {
        self.emission[shape as usize].filter(|_| ng.dot(w) > 0.0)
    }

    fn choice_pmf(&self, light: Option<u32>) -> f32 {
        match (light, &self.light_choice) {
            (Some(l), Some(choice)) => choice.pmf(l as usize) as f32,
            _ => 0.0,
        }
    }

    /// Density per steradian with which emitter sampling from the shading
    /// point `x` draws the direction `d` that reaches shape `shape` at
    /// distance `dist`, where its geometric normal is `ng`: the choice of
    /// the light times [`Sphere::cone_pdf`](super::shape::Sphere::cone_pdf) for a sphere seen from outside,
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

    /// `out[i]`: the density per steradian with which emitter sampling
    /// draws the environment direction `d[i]` (the choice of the
    /// environment among the lights included).
    pub fn environment_pdf_into(&self, d: &[[f32; 3]], out: &mut [f32]) {
        let pmf = self.choice_pmf(self.env_light);
        match &self.environment {
            Some(Environment::Map(env)) => {
                env.pdf_into(d, out, |_| true);
                out.iter_mut().for_each(|p| *p *= pmf);
            }
            Some(env) => out.fill(pmf * env.pdf(Vec3A::Z)),
            None => out.fill(0.0),
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
                        .filter_map(|p| p.intersect(&ray).map(|c| (p, c)))
                        .min_by(|a, b| a.1.t.total_cmp(&b.1.t));
                    if let Some((p, c)) = nearest {
                        let y = p.point(x + d * c.t, c.bary, self.accel.normals());
                        if self.emitted(*shape, y.ng, -d).is_some() {
                            pdf += self.light_pdf(*shape, x, y.ng, d, c.t);
                        }
                    }
                }
                Light::Environment { .. } => {
                    if let Some(env) = &self.environment {
                        pdf += self.choice_pmf(Some(index as u32)) * env.pdf(d);
                    }
                }
            }
        }
        pdf
    }

    /// A sphere around every shape at every time of the shutter: the
    /// sphere around the box of the still shapes' box and the moving
    /// shapes' spheres ([`Mover::bounding_sphere`]); a unit sphere at the
    /// origin for an empty scene. Light from the environment enters the scene
    /// through it ([`Scene::sample_emission`]).
    pub fn bounding_sphere(&self) -> (Vec3A, f32) {
        self.bounding_sphere
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
        let choice = self.light_choice.as_ref()?;
        let index = choice.sample(u[0]);
        let pmf = choice.pmf(index) as f32;
        match &self.lights[index] {
            Light::Environment { .. } => {
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
                    point: primitive.sample(u2, self.accel.normals()),
                    pdf: pmf / area.total_area,
                    radiance: area.radiance,
                })
            }
        }
    }

    /// Emitter sampling from the shading point `x`: a light chosen by power
    /// (`u[0]`), then a point on it (uniformly by area, or for a sphere seen
    /// from outside by the cone it subtends) or an environment
    /// direction by the environment's own sampling (`u[1..3]`; a map's
    /// cell by its [`CellSampler`] from 64 bits of `bits` when given, else
    /// by [`EnvMap::sample`](crate::envmap::EnvMap::sample) of `u[1..3]`, with the same density). `None`
    /// when the scene has no light or the sample carries no radiance.
    #[inline]
    pub fn sample_light(
        &self,
        x: Vec3A,
        u: [f32; 3],
        bits: Option<impl FnOnce() -> u64>,
    ) -> Option<LightSample> {
        let choice = self.light_choice.as_ref()?;
        let index = choice.sample(u[0]);
        let pmf = choice.pmf(index) as f32;
        match &self.lights[index] {
            Light::Environment { cells } => {
                let env = self.environment.as_ref()?;
                let cells = cells.as_ref().zip(bits).map(|(c, bits)| (c, bits()));
                let (d, pdf, radiance) = env.sample([u[1], u[2]], cells);
                (pdf > 0.0).then_some(LightSample {
                    d,
                    dist: f32::INFINITY,
                    pdf: pdf * pmf,
                    radiance,
                    point: None,
                })
            }
            Light::Area(area) => {
                let (primitive, u2) = self.pick_primitive(area, [u[1], u[2]]);
                // A sphere seen from outside: by the cone it subtends.
                let (y, cone_pdf) = match primitive {
                    Primitive::Sphere(s) => match s.sample_cone(x, u2) {
                        Some((y, pdf)) => (y, Some(pdf)),
                        None => (s.sample(u2), None),
                    },
                    _ => (primitive.sample(u2, self.accel.normals()), None),
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
