//! A scene: shapes with their materials and emission, an optional
//! environment, the camera and the film size; and its lights, chosen by
//! power for emitter sampling.

use glam::Vec3A;

use super::accel::{Accel, Hit, LEAF_MAX, Subset};
use super::camera::Camera;
pub use super::environment::Environment;
use super::filter::{FilmFilter, Filter};
use super::geometry::check_primitives;
pub use super::geometry::{Geometry, MAX_PRIMITIVES, affine, daffine};
use super::motion::{Motion, Mover};
use super::shape::{Ray, SurfacePoint};
use crate::alloc;
use crate::distr::Discrete1D;
use crate::error::{Error, Result};
use crate::math::luminance;
use crate::phong::{Phong, VIEW_TERMS};

mod lights;
use lights::{AreaLight, EnvLight, Light, LightChoice};
pub use lights::{ChosenLight, Emission, EnvDensity, InvertedSamples, LightSample};

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
    /// Each shape's BRDF's [`Phong::view_terms`], computed once.
    view_terms: Vec<[f32; VIEW_TERMS]>,
    /// Whether each shape is a sphere (its shading frame:
    /// [`super::integrator::shading`]).
    spheres: Vec<bool>,
    emission: Vec<Option<[f32; 3]>>,
    /// The area lights' primitives, when they are few
    /// ([`Scene::emitters`]).
    emitters: Option<Subset>,
    light_of_shape: Vec<Option<u32>>,
    environment: Option<Environment>,
    env_light: Option<u32>,
    lights: Vec<Light>,
    light_choice: Option<LightChoice>,
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
        let mut meshes = Vec::new();
        let mut materials = Vec::with_capacity(shapes.len());
        let spheres = alloc::collect(
            shapes
                .iter()
                .map(|s| matches!(s.geometry, Geometry::Sphere(_))),
            "the scene's shapes",
        )?;
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
                let mut own_meshes = Vec::new();
                let own = alloc::collect(
                    shape.geometry.into_primitives(&mut own_meshes),
                    "a moving shape's primitives",
                )?;
                let shapes = alloc::collect(own.iter().map(|_| id), "a moving shape's primitives")?;
                movers.push(Mover::new(Accel::new(own, shapes, own_meshes)?, motion));
                materials.push(shape.material);
                emission.push(None);
                light_of_shape.push(None);
                continue;
            }
            let first = primitives.len() as u32;
            primitives.extend(shape.geometry.into_primitives(&mut meshes));
            shape_of.resize(primitives.len(), id);
            materials.push(shape.material);
            let radiance = shape.emission.map(|l| l.map(|v| v as f32));
            emission.push(radiance);
            // The areas of an emitter's primitives, to choose among them.
            let areas = match shape.emission {
                Some(_) => alloc::collect(
                    primitives[first as usize..].iter().map(|p| p.area(&meshes)),
                    "the areas",
                )?,
                None => Vec::new(),
            };
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
        let view_terms = alloc::collect(
            materials.iter().map(|m| m.bsdf.view_terms()),
            "the scene's shapes",
        )?;
        let accel = Accel::new(primitives, shape_of, meshes)?;
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
                lights.push(Light::Environment(EnvLight::new(env)?));
                powers.push(power);
            }
        }
        let light_choice = LightChoice::new(&powers)?;
        let emitting = lights.iter().filter_map(|light| match light {
            Light::Area(a) => Some(a.first..a.first + a.count),
            Light::Environment(_) => None,
        });
        let ids: Vec<u32> = emitting.flatten().take(LEAF_MAX + 1).collect();
        let few = ids.is_empty() || ids.len() <= LEAF_MAX && !accel.is_leaf();
        let emitters = few.then(|| accel.subset(&ids));
        Ok(Scene {
            accel,
            materials,
            view_terms,
            spheres,
            emitters,
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
        self.still_surface(ray, hit)
    }

    /// [`Scene::surface`] of a hit on a shape that stays (any hit, in a
    /// scene without moving shapes: [`Scene::has_movers`]).
    #[inline(always)]
    pub fn still_surface(&self, ray: &Ray, hit: &Hit) -> (u32, SurfacePoint) {
        let primitive = &self.accel.primitives()[hit.primitive as usize];
        (
            self.accel.shape_of(hit.primitive),
            primitive.point(ray.o + ray.d * hit.t, hit.bary, self.accel.meshes()),
        )
    }

    /// Whether some shape moves during the shutter (its hits then need
    /// [`Scene::surface`]'s time).
    #[inline]
    pub fn has_movers(&self) -> bool {
        !self.movers.is_empty()
    }

    /// The primitives of the area lights (those of nonzero power), when
    /// the nearest of them a ray meets is better found without the rest of
    /// the scene: when they are at most [`LEAF_MAX`] (as many as the ray
    /// tracer tests one by one rather than by a BVH) in a scene that is
    /// more than one such leaf (in one leaf, the nearest hit costs no more
    /// than an any-hit test), and always when there are none (an empty
    /// subset: a ray then only leaves the scene or not). Their triangles
    /// are tested as the leaf tests them, which is not watertight as
    /// Embree's robust test is: a ray through the edge two of them share
    /// may miss both.
    #[inline]
    pub fn emitters(&self) -> Option<&Subset> {
        self.emitters.as_ref()
    }

    /// Whether the shape `hit` is on is an area light: [`Scene::is_emitter`]
    /// without the surface point (moving shapes do not emit: [`Scene::new`]
    /// refuses them).
    #[inline]
    pub fn hits_emitter(&self, hit: &Hit) -> bool {
        let still = hit.primitive < self.accel.primitives().len() as u32;
        still && self.is_emitter(self.accel.shape_of(hit.primitive))
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

    /// The view terms of shape `shape`'s BRDF ([`Phong::view_terms`]).
    #[inline]
    pub(crate) fn view_terms(&self, shape: u32) -> &[f32; VIEW_TERMS] {
        &self.view_terms[shape as usize]
    }

    /// Whether shape `shape` is a sphere.
    #[inline]
    pub fn is_sphere(&self, shape: u32) -> bool {
        self.spheres[shape as usize]
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

    /// A sphere around every shape at every time of the shutter: the
    /// sphere around the box of the still shapes' box and the moving
    /// shapes' spheres ([`Mover::bounding_sphere`]); a unit sphere at the
    /// origin for an empty scene. Light from the environment enters the scene
    /// through it ([`Scene::sample_emission`]).
    pub fn bounding_sphere(&self) -> (Vec3A, f32) {
        self.bounding_sphere
    }
}
