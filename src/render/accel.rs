//! The acceleration structure. When Embree is there ([`super::embree`]),
//! the scene's triangles (more than [`LEAF_MAX`] of them) are traced by it
//! and the other primitives (spheres, disks) by obvhs beside it; without
//! it, every primitive by obvhs. obvhs holds its primitives in one
//! compressed wide BVH (CWBVH, built by PLOC), or, when there are at most
//! [`LEAF_MAX`], as a single leaf, which costs a fraction of a wide-node
//! traversal: one ray's test takes its triangles four at a time, a
//! batch's tests each triangle and sphere against a block of rays at SIMD
//! width (`leaf`). Through the
//! BVH, the leaves' primitives are read from a copy in the BVH's order
//! (`Packed`: a triangle's vertex and edges in 40 bytes), so that a leaf
//! is a run of memory rather than a scatter over the meshes' vertices.

use std::sync::Arc;
use std::time::Duration;

use glam::Vec3A;
use obvhs::{BvhBuildParams, aabb::Aabb, cwbvh::CwBvh, cwbvh::builder::build_cwbvh, ray::RayHit};

use crate::alloc;
use crate::error::{Error, Result};

mod leaf;

use super::embree::{self, Stream as EmbreeStream, Triangles as Embree};
use super::geometry::check_primitives;
use super::mesh::Mesh;
use super::shape::{Candidate, Disk, Ray, Sphere, SurfacePoint, Triangle, triangle_hit};
use leaf::Leaf;

/// Working memory of the BVH builder per primitive, checked before it
/// starts: a scene's whole compilation peaked at about 212 bytes a
/// triangle (a 1.3 M-triangle mesh), before the leaves' copy of 40 bytes
/// ([`Packed`]) was added.
const BUILD_BYTES_PER_PRIMITIVE: usize = 300;

/// A primitive of a scene, in 16 bytes: a triangle as the face of a
/// mesh (its vertices and normals stay in the mesh), a sphere or a disk
/// out of line.
#[derive(Clone, Debug)]
pub enum Primitive {
    /// Face `face` of mesh `mesh` ([`Accel::meshes`]).
    Triangle {
        /// The mesh.
        mesh: u32,
        /// The face.
        face: u32,
    },
    /// A sphere.
    Sphere(Box<Sphere>),
    /// A disk.
    Disk(Box<Disk>),
}

impl Primitive {
    /// Its triangle, if it is a face (of one of `meshes`: panics for a
    /// mesh not among them).
    #[inline]
    pub fn triangle(&self, meshes: &[Mesh]) -> Option<Triangle> {
        match *self {
            Primitive::Triangle { mesh, face } => Some(meshes[mesh as usize].triangle(face)),
            _ => None,
        }
    }

    /// The hit of `ray` in `(0, ray.tmax)`, if any (`meshes` those of its
    /// scene, as for every method here).
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, meshes: &[Mesh]) -> Option<Candidate> {
        match self {
            Primitive::Triangle { .. } => self.triangle(meshes)?.intersect(ray),
            Primitive::Sphere(s) => s.intersect(ray),
            Primitive::Disk(d) => d.intersect(ray),
        }
    }

    /// Its area.
    pub fn area(&self, meshes: &[Mesh]) -> f64 {
        match self {
            Primitive::Triangle { mesh, face } => {
                f64::from(meshes[*mesh as usize].triangle(*face).area())
            }
            Primitive::Sphere(s) => s.area(),
            Primitive::Disk(d) => f64::from(d.area),
        }
    }

    /// A point drawn uniformly by area (density `1 / area`).
    #[inline]
    pub fn sample(&self, u: [f32; 2], meshes: &[Mesh]) -> SurfacePoint {
        match self {
            Primitive::Triangle { mesh, face } => meshes[*mesh as usize].sample(*face, u),
            Primitive::Sphere(s) => s.sample(u),
            Primitive::Disk(d) => d.sample(u),
        }
    }

    fn bounds(&self, meshes: &[Mesh]) -> Aabb {
        let (lo, hi) = match self {
            Primitive::Triangle { mesh, face } => {
                let t = meshes[*mesh as usize].triangle(*face);
                let (p1, p2) = (t.p0 + t.e1, t.p0 + t.e2);
                (t.p0.min(p1).min(p2), t.p0.max(p1).max(p2))
            }
            Primitive::Sphere(s) => s.bounds(),
            Primitive::Disk(d) => d.bounds(),
        };
        Aabb::new(lo, hi)
    }

    /// The surface point of a hit on this primitive at `p` (position along
    /// the ray) with barycentrics `bary` (triangles).
    #[inline(always)]
    pub fn point(&self, p: Vec3A, bary: [f32; 2], meshes: &[Mesh]) -> SurfacePoint {
        match self {
            Primitive::Triangle { mesh, face } => meshes[*mesh as usize].point(*face, bary),
            Primitive::Sphere(s) => s.point(p),
            Primitive::Disk(d) => d.point(p),
        }
    }
}

/// The steps of [`Accel::prefetch_point`], in the order they run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ahead {
    /// The primitive's entry and its shape.
    Entry,
    /// A triangle's face (its vertex indices).
    Face,
    /// The face's vertices and vertex normals.
    Vertices,
}

/// The closest hit of a ray.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f32,
    /// Index of the primitive in [`Accel::primitives`] (in a scene with
    /// moving shapes, the primitives of the moving shapes' own BVHs
    /// follow: [`crate::render::Scene::intersect`]).
    pub primitive: u32,
    /// Barycentrics (triangles).
    pub bary: [f32; 2],
}

/// The name of obvhs as a ray tracer ([`Accel::ray_tracer`]).
pub const OBVHS: &str = "obvhs";

/// The most primitives tested directly, without a BVH.
pub const LEAF_MAX: usize = 8;

/// A primitive as the BVH's leaves read it: a triangle's first vertex and
/// edges, with its index in [`Accel::primitives`]; another shape only by
/// its index, with [`Packed::OTHER`] set.
#[derive(Clone, Copy, Debug)]
struct Packed {
    p0: [f32; 3],
    primitive: u32,
    e1: [f32; 3],
    e2: [f32; 3],
}

impl Packed {
    /// The bit of [`Packed::primitive`] that marks a shape other than a
    /// triangle.
    const OTHER: u32 = 1 << 31;

    fn new(primitive: &Primitive, index: u32, meshes: &[Mesh]) -> Self {
        match primitive.triangle(meshes) {
            Some(t) => Packed {
                p0: t.p0.to_array(),
                primitive: index,
                e1: t.e1.to_array(),
                e2: t.e2.to_array(),
            },
            _ => Packed {
                p0: [0.0; 3],
                primitive: index | Self::OTHER,
                e1: [0.0; 3],
                e2: [0.0; 3],
            },
        }
    }
}

/// Primitives, the shape each belongs to, the meshes whose faces the
/// triangles are, their Embree scene (the meshes, when Embree traces them)
/// and the BVH of the others (none for at most [`LEAF_MAX`] primitives).
pub struct Accel {
    embree: Option<Embree>,
    primitives: Vec<Primitive>,
    shape_of: Vec<u32>,
    /// Shared with the Embree scene, which traces their buffers.
    meshes: Arc<[Mesh]>,
    bounds: Option<Aabb>,
    bvh: Option<CwBvh>,
    /// The primitives in the order of the BVH's leaves.
    packed: Vec<Packed>,
    /// The primitives as one leaf, when there is no BVH.
    leaf: Leaf,
}

impl Accel {
    /// Builds the BVH over `primitives`, primitive `i` of shape
    /// `shape_of[i]` (the two as separate lists, so that the build holds
    /// no second copy of the primitives), whose triangles are faces of
    /// `meshes` (each mesh's faces one after the other, in their order, as
    /// the geometry of a shape lists them).
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the BVH's memory cannot be had,
    /// [`crate::Error::Argument`] when the faces are not listed so,
    /// [`crate::Error::TooLarge`] for more than
    /// [`super::geometry::MAX_PRIMITIVES`] primitives.
    ///
    /// # Panics
    /// If the two lists differ in length.
    pub fn new(primitives: Vec<Primitive>, shape_of: Vec<u32>, meshes: Vec<Mesh>) -> Result<Self> {
        Self::build(primitives, shape_of, meshes, true)
    }

    /// [`Accel::new`], with Embree only if `embree` (and as
    /// `MCSAMPLE_RAY_TRACER` says): `false` lets the tests compare the two.
    fn build(
        primitives: Vec<Primitive>,
        shape_of: Vec<u32>,
        meshes: Vec<Mesh>,
        embree: bool,
    ) -> Result<Self> {
        const WHAT: &str = "the BVH";
        let n = primitives.len();
        assert_eq!(shape_of.len(), n, "a shape for every primitive");
        check_primitives("primitives", n)?;
        let meshes: Arc<[Mesh]> = meshes.into();
        let first = first_faces(&primitives, &meshes)?;
        let bounds = primitives
            .iter()
            .map(|p| p.bounds(&meshes))
            .reduce(|a, b| a.union(&b));
        let library = if embree { embree::wanted()? } else { None };
        let is_triangle = |p: &Primitive| matches!(p, Primitive::Triangle { .. });
        let triangles = primitives.iter().filter(|p| is_triangle(p)).count();
        let embree = match library {
            Some(library) if triangles > LEAF_MAX => Some(Embree::new(library, &meshes, &first)?),
            _ => None,
        };
        // What obvhs traces: all, or what Embree does not.
        let mut ids = alloc::with_capacity(n, WHAT)?;
        ids.extend(
            (0..n as u32).filter(|&i| embree.is_none() || !is_triangle(&primitives[i as usize])),
        );
        let aabbs = alloc::collect(
            ids.iter().map(|&i| primitives[i as usize].bounds(&meshes)),
            WHAT,
        )?;
        // The builder allocates as it goes, infallibly: check first that
        // its working memory is there.
        if ids.len() > LEAF_MAX {
            alloc::probe::<u8>(ids.len().saturating_mul(BUILD_BYTES_PER_PRIMITIVE), WHAT)?;
        }
        let bvh = (ids.len() > LEAF_MAX).then(|| {
            build_cwbvh(
                &aabbs,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        });
        let (leaf, packed) = match &bvh {
            Some(bvh) => (
                Default::default(),
                alloc::collect(
                    bvh.primitive_indices.iter().map(|&j| {
                        let i = ids[j as usize];
                        Packed::new(&primitives[i as usize], i, &meshes)
                    }),
                    WHAT,
                )?,
            ),
            None => (Leaf::new(&primitives, &ids, &meshes), Vec::new()),
        };
        Ok(Accel {
            embree,
            primitives,
            shape_of,
            meshes,
            bounds,
            bvh,
            packed,
            leaf,
        })
    }

    /// What traces the triangles: `"embree 3.13.5"` (its version) or
    /// `"obvhs"`.
    pub fn ray_tracer(&self) -> String {
        self.embree
            .as_ref()
            .map_or_else(|| OBVHS.into(), Embree::name)
    }

    /// The primitives, in the order they were given.
    pub fn primitives(&self) -> &[Primitive] {
        &self.primitives
    }

    /// The meshes whose faces the triangles are.
    #[inline]
    pub fn meshes(&self) -> &[Mesh] {
        &self.meshes
    }

    /// The shape a primitive belongs to.
    #[inline]
    pub fn shape_of(&self, primitive: u32) -> u32 {
        self.shape_of[primitive as usize]
    }

    /// Asks the caches for what [`Primitive::point`] of a hit on
    /// `primitive` and [`Accel::shape_of`] it will read, in the `step` of
    /// three some hits apart, each reading what the one before brought
    /// ([`crate::simd::prefetch`]: hints only, which never fault; no
    /// table is read past its end).
    #[inline(always)]
    pub fn prefetch_point(&self, primitive: u32, step: Ahead) {
        let i = primitive as usize;
        if step == Ahead::Entry {
            crate::simd::prefetch(&self.primitives, i);
            crate::simd::prefetch(&self.shape_of, i);
        } else if let Some(&Primitive::Triangle { mesh, face }) = self.primitives.get(i)
            && let Some(mesh) = self.meshes.get(mesh as usize)
        {
            mesh.prefetch_point(face, step == Ahead::Vertices);
        }
    }

    /// The nearest hit in `(0, ray.tmax)`. Inlined for scenes of one leaf
    /// (whose test is short: a call, and the hit returned through memory,
    /// would cost a good part of it).
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        match (self.embree.as_ref(), self.bvh.as_ref()) {
            (None, None) => self.leaf.intersect(ray),
            (None, Some(bvh)) => self.intersect_bvh(bvh, ray),
            (Some(embree), _) => self.intersect_embree(embree, ray),
        }
    }

    /// [`Accel::intersect`] when Embree traces the triangles: its nearest
    /// hit, then the others' nearer than it.
    #[inline(never)]
    fn intersect_embree(&self, embree: &Embree, ray: &Ray) -> Option<Hit> {
        self.nearer_other(ray, embree.intersect(ray))
    }

    /// `hit` (Embree's, on a triangle), or the hit of `ray` on another
    /// primitive nearer than it.
    #[inline]
    fn nearer_other(&self, ray: &Ray, hit: Option<Hit>) -> Option<Hit> {
        let shrunk = Ray {
            tmax: hit.map_or(ray.tmax, |h| h.t),
            ..*ray
        };
        let other = match self.bvh.as_ref() {
            None => self.leaf.intersect(&shrunk),
            Some(bvh) => self.intersect_bvh(bvh, &shrunk),
        };
        other.or(hit)
    }

    /// [`Accel::intersect`] of each ray of `rays` (`coherent` ones, such
    /// as the camera rays of pixels, or not), appended to `out`; with
    /// Embree, the triangles traced as one stream (`stream` its working
    /// memory).
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the stream's memory cannot be had.
    pub fn intersect_many(
        &self,
        rays: &[Ray],
        coherent: bool,
        stream: &mut EmbreeStream,
        out: &mut Vec<Option<Hit>>,
    ) -> Result<()> {
        let first = out.len();
        match self.embree.as_ref() {
            Some(embree) => embree.intersect_many(rays, coherent, stream, out)?,
            None => {
                alloc::reserve(out, rays.len(), "the hits")?;
                out.resize(first + rays.len(), None);
            }
        }
        let hits = &mut out[first..];
        match (self.bvh.as_ref(), self.embree.as_ref()) {
            (None, None) => self.leaf.intersect_fresh(rays, hits),
            (None, Some(_)) => self.leaf.intersect_many(rays, hits),
            (Some(_), _) => {
                for (ray, hit) in rays.iter().zip(hits) {
                    *hit = self.nearer_other(ray, *hit);
                }
            }
        }
        Ok(())
    }

    /// [`Accel::intersect`] through the BVH.
    #[inline(never)]
    fn intersect_bvh(&self, bvh: &CwBvh, ray: &Ray) -> Option<Hit> {
        let mut best = Hit {
            t: ray.tmax,
            primitive: 0,
            bary: [0.0; 2],
        };
        let mut hit = RayHit::none();
        let query = obvhs::ray::Ray::new(ray.o, ray.d, 0.0, ray.tmax);
        bvh.ray_traverse(query, &mut hit, |r, id| {
            let shrunk = Ray {
                tmax: r.tmax,
                ..*ray
            };
            match self.intersect_packed(id, &shrunk) {
                Some((primitive, c)) => {
                    best = Hit {
                        t: c.t,
                        primitive,
                        bary: c.bary,
                    };
                    c.t
                }
                None => f32::INFINITY,
            }
        });
        (best.t < ray.tmax).then_some(best)
    }

    /// The hit of `ray` on the primitive at position `id` of the BVH's
    /// leaves, with that primitive's index.
    #[inline(always)]
    fn intersect_packed(&self, id: usize, ray: &Ray) -> Option<(u32, Candidate)> {
        let p = &self.packed[id];
        if p.primitive & Packed::OTHER != 0 {
            let primitive = p.primitive & !Packed::OTHER;
            let c = self.primitives[primitive as usize].intersect(ray, &self.meshes)?;
            return Some((primitive, c));
        }
        triangle_hit(ray, p.p0, p.e1, p.e2).map(|c| (p.primitive, c))
    }

    /// Whether anything lies on the ray in `(0, ray.tmax)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.embree.as_ref().is_some_and(|e| e.occluded(ray)) || self.others_occlude(ray)
    }

    /// [`Accel::occluded`] of each ray of `rays`, appended to `out`; with
    /// Embree, the triangles traced as one stream (`stream` its working
    /// memory).
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the stream's memory cannot be had.
    pub fn occluded_many(
        &self,
        rays: &[Ray],
        stream: &mut EmbreeStream,
        out: &mut Vec<bool>,
    ) -> Result<()> {
        let first = out.len();
        match self.embree.as_ref() {
            Some(embree) => embree.occluded_many(rays, stream, out)?,
            None => {
                alloc::reserve(out, rays.len(), "the shadow rays")?;
                out.resize(first + rays.len(), false);
            }
        }
        let blocked = &mut out[first..];
        match self.bvh {
            None => self.leaf.occluded_many(rays, blocked),
            Some(_) => {
                for (ray, blocked) in rays.iter().zip(blocked) {
                    *blocked = *blocked || self.others_occlude(ray);
                }
            }
        }
        Ok(())
    }

    /// Whether a primitive that Embree does not trace (all of them without
    /// Embree) lies on the ray in `(0, ray.tmax)`.
    #[inline]
    fn others_occlude(&self, ray: &Ray) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return self.leaf.occludes(ray);
        };
        let query = obvhs::ray::Ray::new(ray.o, ray.d, 0.0, ray.tmax);
        !bvh.ray_traverse_miss(query, |_, id| {
            self.intersect_packed(id, ray)
                .map_or(f32::INFINITY, |(_, c)| c.t)
        })
    }

    /// Bounds of the whole scene, or `None` when it has no primitive.
    pub fn bounds(&self) -> Option<(Vec3A, Vec3A)> {
        self.bounds.map(|b| (b.min, b.max))
    }

    /// Whether the primitives are one leaf (at most [`LEAF_MAX`], all
    /// tested against each ray).
    pub fn is_leaf(&self) -> bool {
        self.embree.is_none() && self.bvh.is_none()
    }

    /// The primitives `ids` alone, all tested against each ray (for a few
    /// of them: [`Subset`]).
    pub fn subset(&self, ids: &[u32]) -> Subset {
        Subset(Leaf::new(&self.primitives, ids, &self.meshes))
    }
}

/// A few of a scene's primitives (an area light's, say), all tested
/// against each ray, a block of rays at a time at SIMD width, without the
/// rest of the scene.
pub struct Subset(Leaf);

impl Subset {
    /// The nearest hit of each ray of `rays` on these primitives (primitive
    /// numbers as in the whole scene), into `hits` (of the same length).
    pub fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.0.intersect_fresh(rays, hits);
    }
}

/// The number among `primitives` of each mesh's first face (0 for a mesh
/// of no faces, which Embree is not given), after checking that every
/// mesh's faces are listed once each, one after the other, in their order,
/// as Embree numbers them.
///
/// # Errors
/// [`Error::Argument`] when they are not, [`Error::Memory`] when the list
/// cannot be had.
fn first_faces(primitives: &[Primitive], meshes: &[Mesh]) -> Result<Vec<u32>> {
    let mut first = alloc::filled(meshes.len(), 0, "the meshes")?;
    let mut listed = alloc::filled(meshes.len(), 0_usize, "the meshes")?;
    for (i, p) in primitives.iter().enumerate() {
        if let Primitive::Triangle { mesh, face } = *p {
            let m = mesh as usize;
            if face == 0 && m < meshes.len() {
                first[m] = i as u32;
            }
            if m >= meshes.len()
                || face as usize != listed[m]
                || i != first[m] as usize + face as usize
            {
                return Err(Error::Argument {
                    arg: "primitives",
                    message: format!(
                        "primitive {i}, face {face} of mesh {mesh}, is not where the faces of \
                         its mesh ({} meshes) are listed in order",
                        meshes.len()
                    ),
                });
            }
            listed[m] += 1;
        }
    }
    if let Some(m) = (0..meshes.len()).find(|&m| listed[m] != meshes[m].faces().len()) {
        return Err(Error::Argument {
            arg: "primitives",
            message: format!(
                "mesh {m} has {} faces, {} of them listed",
                meshes[m].faces().len(),
                listed[m]
            ),
        });
    }
    Ok(first)
}

#[cfg(test)]
mod tests;
