//! The primitives of a scene without a BVH (at most [`super::LEAF_MAX`]
//! that obvhs would trace), all tested against each ray: one ray at a time
//! (its triangles four at once, [`Triangles4`]), or a block of rays at once,
//! each triangle and sphere tested against the whole block at SIMD width
//! ([`Leaf::intersect_many`], [`Leaf::occluded_many`]; the disks after,
//! ray by ray). Both run the same
//! arithmetic in the same order, so they find the same hits, bit for bit.

use super::{Hit, Primitive};
use crate::render::mesh::Mesh;
use crate::render::shape::{Candidate, Disk, Ray, Sphere, Triangle, Triangles4, moller_trumbore};
use crate::simd::{self, Level, OnLines};

/// Rays per block of the batch tests (the loops over a block's rays
/// vectorise; 64 keeps a block's columns within the L1 cache).
const BLOCK: usize = 64;

/// The primitive number of "no hit" in a block's best hits.
const NONE: u32 = u32::MAX;

/// A triangle's vertex `p0` and edges `e1`, `e2`, by components.
type VertexEdges = [[f32; 3]; 3];

/// The primitives of a scene without a BVH, for testing all of them.
#[derive(Default)]
pub(super) struct Leaf {
    /// The triangles, four to a pack, with their primitive indices (one
    /// ray at a time).
    packs: Vec<(Triangles4, [u32; 4])>,
    /// The same triangles one by one, in the same order (a block of rays
    /// at a time).
    triangles: Vec<(VertexEdges, u32)>,
    /// The spheres, copied in (a test reads no further), with their
    /// primitive indices.
    spheres: Vec<(Sphere, u32)>,
    /// The disks, likewise.
    disks: Vec<(Disk, u32)>,
}

impl Leaf {
    /// Sorts the primitives `ids` of `primitives` into triangles (in packs
    /// of four and one by one), spheres and disks.
    pub(super) fn new(primitives: &[Primitive], ids: &[u32], meshes: &[Mesh]) -> Self {
        let (mut triangles, mut leaf) = (Vec::new(), Leaf::default());
        for &i in ids {
            match &primitives[i as usize] {
                Primitive::Triangle { mesh, face } => {
                    triangles.push((meshes[*mesh as usize].triangle(*face), i));
                }
                Primitive::Sphere(s) => leaf.spheres.push((**s, i)),
                Primitive::Disk(d) => leaf.disks.push((**d, i)),
            }
        }
        leaf.packs = triangles
            .chunks(4)
            .map(|c| {
                let (t, i): (Vec<Triangle>, Vec<u32>) = c.iter().copied().unzip();
                (
                    Triangles4::new(&t),
                    std::array::from_fn(|l| i.get(l).copied().unwrap_or(0)),
                )
            })
            .collect();
        leaf.triangles = triangles
            .iter()
            .map(|(t, i)| ([t.p0, t.e1, t.e2].map(|v| v.to_array()), *i))
            .collect();
        leaf
    }

    /// The nearest hit of `ray` in `(0, ray.tmax)`: the triangles (a pack
    /// at a time), then the spheres, then the disks, each tested against
    /// the ray shortened to the nearest hit so far.
    #[inline(always)]
    pub(super) fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut shrunk = *ray;
        for (pack, index) in &self.packs {
            if let Some((lane, c)) = pack.intersect(&shrunk) {
                nearer(&mut best, &mut shrunk, index[lane], c);
            }
        }
        for (sphere, primitive) in &self.spheres {
            if let Some(c) = sphere.intersect(&shrunk) {
                nearer(&mut best, &mut shrunk, *primitive, c);
            }
        }
        for (disk, primitive) in &self.disks {
            if let Some(c) = disk.intersect(&shrunk) {
                nearer(&mut best, &mut shrunk, *primitive, c);
            }
        }
        best
    }

    /// Whether a primitive lies on `ray` in `(0, ray.tmax)`.
    #[inline]
    pub(super) fn occludes(&self, ray: &Ray) -> bool {
        self.packs.iter().any(|(pack, _)| pack.occludes(ray))
            || self.spheres.iter().any(|(s, _)| s.occludes(ray))
            || self.disks.iter().any(|(d, _)| d.intersect(ray).is_some())
    }

    /// For each ray of `rays` and its hit so far in `hits` (another ray
    /// tracer's, or `None`), the hit of [`Leaf::intersect`] on the ray
    /// shortened to it if there is one, else the hit so far: what
    /// `leaf.intersect(shortened).or(hits[i])` gives, bit for bit. The
    /// triangles and spheres are tested against [`BLOCK`] rays at once, at
    /// SIMD width.
    pub(super) fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.by_blocks(
            rays,
            hits,
            #[inline(always)]
            |rays, hits, level| self.intersect_block::<false>(rays, hits, level),
        );
    }

    /// [`Leaf::intersect`] of each ray of `rays`, into `hits` (whatever
    /// they held): [`Leaf::intersect_many`] with no hits so far, without
    /// reading them.
    pub(super) fn intersect_fresh(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        if self.triangles.is_empty() && self.spheres.is_empty() && self.disks.is_empty() {
            hits.fill(None);
            return;
        }
        self.by_blocks(
            rays,
            hits,
            #[inline(always)]
            |rays, hits, level| self.intersect_block::<true>(rays, hits, level),
        );
    }

    /// [`Leaf::intersect_many`] of at most [`BLOCK`] rays; with `FRESH`,
    /// [`Leaf::intersect_fresh`]'s.
    #[inline(always)]
    fn intersect_block<const FRESH: bool>(
        &self,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        level: Level,
    ) {
        let block = Block::new(rays, level);
        let mut best = if FRESH {
            Best::fresh(rays)
        } else {
            Best::new(rays, hits)
        };
        for &([p0, e1, e2], id) in &self.triangles {
            for i in 0..BLOCK {
                let scaled = moller_trumbore(block.o(i), block.d(i), p0, e1, e2);
                let (ahead, t, bary) = scaled.hit(best.t[i]);
                best.take(i, scaled.inside & ahead, t, id, bary);
            }
        }
        for &(sphere, id) in self.spheres.iter().filter(|(s, _)| block.comes_near(s)) {
            for i in 0..BLOCK {
                let (take, t) = sphere.hit_branchless(block.o(i), block.d(i), best.t[i]);
                best.take(i, take, t, id, [0.0; 2]);
            }
        }
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
            let mut nearest = best.hit(i);
            let mut shrunk = Ray {
                tmax: best.t[i],
                ..*ray
            };
            for (disk, id) in &self.disks {
                if let Some(c) = disk.intersect(&shrunk) {
                    nearer(&mut nearest, &mut shrunk, *id, c);
                }
            }
            *hit = nearest;
        }
    }

    /// `blocked[i] ||` [`Leaf::occludes`] of `rays[i]`, for each, the
    /// triangles and spheres tested against [`BLOCK`] rays at once.
    pub(super) fn occluded_many(&self, rays: &[Ray], blocked: &mut [bool]) {
        self.by_blocks(
            rays,
            blocked,
            #[inline(always)]
            |rays, blocked, level| self.occluded_block(rays, blocked, level),
        );
    }

    /// `test` of each block of at most [`BLOCK`] rays of `rays` and their
    /// rows of `out`, compiled for the widest vector unit
    /// ([`simd::dispatch`], whose level `test` is given); nothing at all for
    /// an empty leaf.
    #[inline(always)]
    fn by_blocks<T>(&self, rays: &[Ray], out: &mut [T], test: impl Fn(&[Ray], &mut [T], Level)) {
        debug_assert_eq!(rays.len(), out.len());
        if self.triangles.is_empty() && self.spheres.is_empty() && self.disks.is_empty() {
            return;
        }
        simd::dispatch(
            #[inline(always)]
            |level| {
                for (rays, out) in rays.chunks(BLOCK).zip(out.chunks_mut(BLOCK)) {
                    test(rays, out, level);
                }
            },
        );
    }

    /// [`Leaf::occluded_many`] of at most [`BLOCK`] rays.
    #[inline(always)]
    fn occluded_block(&self, rays: &[Ray], blocked: &mut [bool], level: Level) {
        let block = Block::new(rays, level);
        let OnLines(tmax) = &mut OnLines([0.0; BLOCK]);
        let OnLines(any) = &mut OnLines([false; BLOCK]);
        for (i, (ray, &b)) in rays.iter().zip(&*blocked).enumerate() {
            tmax[i] = ray.tmax;
            any[i] = b;
        }
        for &([p0, e1, e2], _) in &self.triangles {
            for i in 0..BLOCK {
                let scaled = moller_trumbore(block.o(i), block.d(i), p0, e1, e2);
                any[i] |= scaled.inside & scaled.hit(tmax[i]).0;
            }
        }
        for (sphere, _) in self.spheres.iter().filter(|(s, _)| block.comes_near(s)) {
            for i in 0..BLOCK {
                any[i] |= sphere.occludes_branchless(block.o(i), block.d(i), tmax[i]);
            }
        }
        for (i, (ray, b)) in rays.iter().zip(blocked).enumerate() {
            *b = any[i] || self.disks.iter().any(|(d, _)| d.intersect(ray).is_some());
        }
    }
}

/// A block's ray origins and directions, one array per component (`x, y,
/// z` of the origins, then of the directions; the rows past the block's
/// rays are zero), on cache-line boundaries.
#[repr(align(64))]
struct Block {
    od: [[f32; BLOCK]; 6],
    /// How many rows hold rays (the rest are zeros).
    rows: usize,
}

impl Block {
    /// The block of `rays` (at most [`BLOCK`]), in code compiled for
    /// `level`: on AVX-512 by transposes in registers
    /// ([`simd::vector_pairs_to_columns`]).
    #[inline(always)]
    fn new(rays: &[Ray], level: Level) -> Self {
        let mut block = Block {
            od: [[0.0; BLOCK]; 6],
            rows: rays.len().min(BLOCK),
        };
        let rays = &rays[..block.rows];
        if simd::vector_pairs_to_columns(rays, |r| [r.o, r.d], &mut block.od, level) {
            return block;
        }
        for (i, ray) in rays.iter().enumerate() {
            for k in 0..3 {
                block.od[k][i] = ray.o[k];
                block.od[3 + k][i] = ray.d[k];
            }
        }
        block
    }

    /// Whether the line of some ray of the block meets `sphere`
    /// ([`Sphere::line_meets`]): if none does, no ray hits it, and its
    /// tests (a square root and divisions in `f64` per ray) can be
    /// skipped. Coherent rays (a few pixels' camera rays, their shadow
    /// rays) mostly pass a small sphere by together.
    /// (A fold over every row with `|` and `&`, not `any`: without
    /// branches, it vectorises. The rows past the rays, zeros, would count
    /// as meeting every sphere.)
    #[inline(always)]
    fn comes_near(&self, sphere: &Sphere) -> bool {
        (0..BLOCK).fold(false, |any, i| {
            any | ((i < self.rows) & sphere.line_meets(self.o(i), self.d(i)))
        })
    }

    #[inline(always)]
    fn o(&self, i: usize) -> [f32; 3] {
        [self.od[0][i], self.od[1][i], self.od[2][i]]
    }

    #[inline(always)]
    fn d(&self, i: usize) -> [f32; 3] {
        [self.od[3][i], self.od[4][i], self.od[5][i]]
    }
}

/// The nearest hit so far of each ray of a block: distance, primitive
/// ([`NONE`] for none) and barycentrics. Rows past the block's rays have
/// distance 0, so that nothing is nearer. On cache-line boundaries.
#[repr(align(64))]
struct Best {
    t: [f32; BLOCK],
    primitive: [u32; BLOCK],
    bary: [[f32; BLOCK]; 2],
}

impl Best {
    /// The hits so far `hits` of `rays`, or their `tmax` where there is
    /// none.
    #[inline(always)]
    fn new(rays: &[Ray], hits: &[Option<Hit>]) -> Self {
        let mut best = Best {
            t: [0.0; BLOCK],
            primitive: [NONE; BLOCK],
            bary: [[0.0; BLOCK]; 2],
        };
        for (i, (ray, hit)) in rays.iter().zip(hits).enumerate().take(BLOCK) {
            best.t[i] = hit.map_or(ray.tmax, |h| h.t);
            best.primitive[i] = hit.map_or(NONE, |h| h.primitive);
            [best.bary[0][i], best.bary[1][i]] = hit.map_or([0.0; 2], |h| h.bary);
        }
        best
    }

    /// No hits yet on `rays`: their `tmax`.
    #[inline(always)]
    fn fresh(rays: &[Ray]) -> Self {
        let mut best = Best {
            t: [0.0; BLOCK],
            primitive: [NONE; BLOCK],
            bary: [[0.0; BLOCK]; 2],
        };
        for (t, ray) in best.t.iter_mut().zip(rays) {
            *t = ray.tmax;
        }
        best
    }

    /// Row `i` becomes the hit at `t` on `primitive` where `take`, without
    /// a branch.
    #[inline(always)]
    fn take(&mut self, i: usize, take: bool, t: f32, primitive: u32, bary: [f32; 2]) {
        self.t[i] = if take { t } else { self.t[i] };
        self.primitive[i] = if take { primitive } else { self.primitive[i] };
        self.bary[0][i] = if take { bary[0] } else { self.bary[0][i] };
        self.bary[1][i] = if take { bary[1] } else { self.bary[1][i] };
    }

    /// Row `i` as a hit, if any.
    #[inline(always)]
    fn hit(&self, i: usize) -> Option<Hit> {
        (self.primitive[i] != NONE).then_some(Hit {
            t: self.t[i],
            primitive: self.primitive[i],
            bary: [self.bary[0][i], self.bary[1][i]],
        })
    }
}

/// `c`, the hit of a ray on `primitive`, as the `best` so far, and the
/// ray `shrunk` to it.
#[inline(always)]
fn nearer(best: &mut Option<Hit>, shrunk: &mut Ray, primitive: u32, c: Candidate) {
    *best = Some(Hit {
        t: c.t,
        primitive,
        bary: c.bary,
    });
    shrunk.tmax = c.t;
}
