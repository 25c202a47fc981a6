//! The shading of a bounce's paths, in three steps over the whole bounce:
//!
//! ```text
//! begin   each path at its hit: its emission (Bounce::emit), and its
//!         row of the BSDF kernel (Bounce::begin: the shading normal, the
//!         view's direction, the light sample's direction, density and
//!         radiance, the BSDF sample's numbers, the BRDF's terms; an
//!         environment map's light sample written later, when the
//!         bounce's are drawn together: KernelRows::set_light)
//! kernel  every row at SIMD width (bsdf_kernel): the shading frame, the
//!         BRDF and its density toward the light sample and the light
//!         that sample carries (MIS weight, cosine), and the BSDF sample
//!         with its direction in world space
//! finish  each path: its light sample's light kept with its shadow ray,
//!         its next ray, roulette
//! ```
//!
//! The kernel holds what costs most per vertex (the frame's division, three
//! powers, two sines and cosines, the mirror's frame, the MIS weight's
//! divisions, the next direction's square root), which one path at a time
//! would compute in scalar code. It computes both parts' directions and
//! selects, where one path at a time draws only the chosen part's
//! direction: the same bits (`PhongView::eval_pdf_one`,
//! `PhongView::sample_one`). The rows of BRDFs without a glossy part
//! (diffuse surfaces) go to a kernel of their own, without the lobe and the
//! glossy direction (one sine and cosine, no power): the same bits again
//! (`PhongView::eval_pdf_diffuse`, `PhongView::sample_diffuse`).

use glam::Vec3A;

use super::{Path, Unshadowed};
use crate::error::Result;
use crate::frame::Frame;
use crate::math::V3;
use crate::mis::Heuristic;
use crate::phong::{PhongView, VIEW_TERMS};
use crate::render::integrator::{
    Integrator, Settings, Strategy, add_scaled, dims, emission_weight, ends_after_light,
    facing_normal, mul, offset, shadow_ray, turns_with_azimuth,
};
use crate::render::scene::{LightSample, Scene};
use crate::render::shape::{Ray, SurfacePoint};
use crate::sampler::Sampler;
use crate::simd;

/// Numbers per row into [`bsdf_kernel`], all in world space: the shading
/// normal (3) and whether the frame turns with the azimuth (1: 1 or 0,
/// [`Frame::around`]), the view's direction `wi` (3), the light sample's
/// direction (3), density and radiance (1 + 3; zeros without one), the
/// BSDF sample's numbers `u0, u1, part` (3) and the BRDF's
/// [`crate::phong::Phong::view_terms`].
pub(super) const BSDF_IN: usize = 17 + VIEW_TERMS;

/// Numbers per row out of [`bsdf_kernel`]: the light sample's light
/// `f_r · L` (3) and its scale `w |cos θ_l| / p_l` (1), whether the sample
/// is to be connected (1: 1 or 0; `p_l > 0` and `f_r > 0` in some
/// channel), then the BSDF sample's direction in world space (3), density
/// and weight (3). The light's four are meaningless (the scale NaN:
/// `p_l = 0`) in a row without a light sample, which is never connected.
pub(super) const BSDF_OUT: usize = 12;

/// What [`Bounce::finish`] needs of a path's [`Bounce::begin`].
#[derive(Clone, Copy, Debug)]
pub(super) struct Begun {
    /// The path's index at the bounce's start (of its surface and of its
    /// numbers drawn beforehand; the environment map's samples drawn
    /// together are handed back by it).
    pub k: u32,
    /// Its row's index in its group of [`KernelRows`] ([`KernelRows::push`]).
    pub row: u32,
    /// Whether it ends after its light sample (emitter sampling, whose
    /// next vertex's emission would not count).
    pub ends: bool,
    /// Whether its BRDF has no glossy part (`ρs = 0`: its row goes to
    /// the kernel without the lobe, [`KernelRows`]).
    pub diffuse: bool,
    /// Whether its light sample is a point on an area light (its shadow
    /// ray ends there): the next of the bounce's points, which are kept
    /// in the paths' order.
    pub to_point: bool,
}

/// The row of [`BSDF_IN`] numbers of [`bsdf_kernel`] at a vertex whose
/// shading normal is `n` (its frame [`Frame::around`] `n` and
/// `azimuthal`), seen along `wi`, with the light sample's direction,
/// density and radiance `light` (if any), the BSDF sample's numbers `u`
/// and `part`, and the BRDF of `terms`.
#[inline]
pub(super) fn bsdf_row(
    ((n, azimuthal), wi): ((V3<f32>, bool), V3<f32>),
    light: Option<(V3<f32>, f32, [f32; 3])>,
    (u, part): ([f32; 2], f32),
    terms: &[f32; VIEW_TERMS],
) -> [f32; BSDF_IN] {
    let mut row = [0.0; BSDF_IN];
    row[..3].copy_from_slice(&n);
    row[3] = if azimuthal { 1.0 } else { 0.0 };
    row[4..7].copy_from_slice(&wi);
    set_row_light(&mut row, light.unwrap_or(([0.0; 3], 0.0, [0.0; 3])));
    row[14..17].copy_from_slice(&[u[0], u[1], part]);
    row[17..].copy_from_slice(terms);
    row
}

/// The light sample's direction, density and radiance written into `row`
/// ([`bsdf_row`]).
#[inline]
fn set_row_light(row: &mut [f32; BSDF_IN], (wl, pdf, radiance): (V3<f32>, f32, [f32; 3])) {
    row[7..10].copy_from_slice(&wl);
    row[10] = pdf;
    row[11..14].copy_from_slice(&radiance);
}

/// The light sample's direction in `row` ([`bsdf_row`]).
#[inline]
fn light_direction(row: &[f32; BSDF_IN]) -> Vec3A {
    Vec3A::new(row[7], row[8], row[9])
}

/// The light sample `ls` as [`bsdf_row`] takes it: its direction, density
/// and radiance.
#[inline]
fn light_of(ls: &LightSample) -> (V3<f32>, f32, [f32; 3]) {
    (ls.d.to_array(), ls.pdf, ls.radiance)
}

/// The BSDF's part of a vertex's shading, for one row of [`BSDF_IN`]
/// numbers ([`bsdf_row`]), in the shading frame [`Frame::around`] the
/// row's normal: with `LIGHT`, toward the light sample's direction `wl`
/// (density `p_l`, radiance `L`), `f_r(wi, wl) · L`,
/// `w |cos θ_l| / p_l` and whether to connect it (`p_l > 0`, none
/// without a light sample, and `f_r > 0`), where `(f_r, p)` is
/// [`PhongView::eval_pdf`] and the MIS weight `w` is `mis`'s `w(p_l, p)` (1 without MIS); with `SAMPLE`,
/// the sample [`PhongView::sample`] of `[u0, u1, part]`, its direction
/// taken to world space and normalised; as [`BSDF_OUT`] numbers (zeros for
/// the part not asked for: under BSDF sampling the light's power is
/// skipped, and where every path ends after its light sample, the
/// sample's two). `GLOSSY` is the general kernel, right for every row;
/// without it, for rows of BRDFs without a glossy part only, by their
/// diffuse forms (no lobe: the same bits, [`PhongView::eval_pdf_diffuse`],
/// [`PhongView::sample_diffuse`]). Branch-free, for
/// [`crate::simd::map_rows`].
#[inline(always)]
pub(super) fn bsdf_kernel<const LIGHT: bool, const SAMPLE: bool, const GLOSSY: bool>(
    row: [f32; BSDF_IN],
    mis: Option<Heuristic>,
) -> [f32; BSDF_OUT] {
    let [
        n0,
        n1,
        n2,
        azimuthal,
        w0,
        w1,
        w2,
        l0,
        l1,
        l2,
        pdf_l,
        e0,
        e1,
        e2,
        u0,
        u1,
        part,
        terms @ ..,
    ] = row;
    let frame = Frame::around([n0, n1, n2], azimuthal > 0.0);
    let view = PhongView::from_terms(frame.to_local([w0, w1, w2]), terms);
    let ([c0, c1, c2], scale, lit) = if LIGHT {
        let wl = frame.to_local([l0, l1, l2]);
        let (f, pdf) = if GLOSSY {
            view.eval_pdf(wl)
        } else {
            view.eval_pdf_diffuse(wl)
        };
        let w = mis.map_or(1.0, |h| h.weight(pdf_l, pdf));
        let lit = ((f[0] > 0.0) | (f[1] > 0.0) | (f[2] > 0.0)) & (pdf_l > 0.0);
        let lit = if lit { 1.0 } else { 0.0 };
        (mul(f, [e0, e1, e2]), w * wl[2].abs() / pdf_l, lit)
    } else {
        ([0.0; 3], 0.0, 0.0)
    };
    let ([x, y, z], pdf, [r, g, b]) = if SAMPLE {
        let s = if GLOSSY {
            view.sample([u0, u1, part])
        } else {
            view.sample_diffuse([u0, u1])
        };
        // `v / √((x² + y²) + z²)`: the bits of glam's `Vec3A::normalize`
        // on x86-64 (its SSE2 form divides by the length).
        let [x, y, z] = frame.to_world(s.wo);
        let length = (x * x + y * y + z * z).sqrt();
        ([x / length, y / length, z / length], s.pdf, s.weight)
    } else {
        ([0.0; 3], 0.0, [0.0; 3])
    };
    [c0, c1, c2, scale, lit, x, y, z, pdf, r, g, b]
}

/// A bounce's rows of [`bsdf_kernel`] and its rows out, in two groups of
/// their own kernel each: the rows of BRDFs without a glossy part
/// ([`Begun::diffuse`], the kernel without the lobe) and the others (the
/// general kernel, right for any row), each group in the paths' order.
#[derive(Default)]
pub(super) struct KernelRows {
    diffuse: Rows,
    glossy: Rows,
}

/// One group's rows in and out.
#[derive(Default)]
struct Rows {
    rows: Vec<[f32; BSDF_IN]>,
    out: Vec<[f32; BSDF_OUT]>,
}

impl KernelRows {
    /// Every row forgotten, and room for `n` rows in each group (either
    /// may hold them all; `what`: the rows' owner, for the error).
    ///
    /// # Errors
    /// [`crate::Error::Memory`] when the memory cannot be had.
    pub fn reserve(&mut self, n: usize, what: &'static str) -> Result<()> {
        let (d, g) = (&mut self.diffuse, &mut self.glossy);
        d.rows.clear();
        d.out.clear();
        g.rows.clear();
        g.out.clear();
        crate::alloc::reserve_each!(n, what; d.rows, d.out, g.rows, g.out)
    }

    /// Every row in forgotten (a bounce's start).
    pub fn clear(&mut self) {
        self.diffuse.rows.clear();
        self.glossy.rows.clear();
    }

    /// The row of the next path, in the diffuse group or not; its index in
    /// its group.
    #[inline]
    pub fn push(&mut self, diffuse: bool, row: [f32; BSDF_IN]) -> u32 {
        let group = self.group(diffuse);
        group.rows.push(row);
        (group.rows.len() - 1) as u32
    }

    /// The light sample `ls`, the environment's (an area light's point
    /// would have no place: [`Begun::to_point`]), written into the row of
    /// the path `begun`.
    #[inline]
    pub fn set_light(&mut self, begun: &Begun, ls: &LightSample) {
        debug_assert!(ls.point.is_none(), "an area light's sample written later");
        if let Some(row) = self.group(begun.diffuse).rows.get_mut(begun.row as usize) {
            set_row_light(row, light_of(ls));
        }
    }

    #[inline]
    fn group(&mut self, diffuse: bool) -> &mut Rows {
        if diffuse {
            &mut self.diffuse
        } else {
            &mut self.glossy
        }
    }

    /// [`bsdf_kernel`] of every row, for a bounce of `settings` at
    /// `depth`: the light's part where the strategy draws light samples,
    /// the BSDF sample's where the paths go on after them.
    pub fn run(&mut self, settings: &Settings, depth: u32) {
        type Mis = Option<Heuristic>;
        fn map<const LIGHT: bool, const SAMPLE: bool>(d: &mut Rows, g: &mut Rows, mis: Mis) {
            fn one<const LIGHT: bool, const SAMPLE: bool, const GLOSSY: bool>(
                group: &mut Rows,
                mis: Mis,
            ) {
                // Through a closure marked inline: given the function
                // itself, the kernel ran 50 % slower (demo BSDF sampling
                // 20.4 -> 30.6 ms).
                let kernel = {
                    #[inline(always)]
                    |row| bsdf_kernel::<LIGHT, SAMPLE, GLOSSY>(row, mis)
                };
                group.out.clear();
                group.out.resize(group.rows.len(), [0.0; BSDF_OUT]);
                simd::map_rows(&mut group.out, &group.rows, &kernel, |_| true, false);
            }
            one::<LIGHT, SAMPLE, false>(d, mis);
            one::<LIGHT, SAMPLE, true>(g, mis);
        }
        let mis = (settings.strategy == Strategy::Mis).then_some(settings.heuristic);
        let light = settings.strategy != Strategy::Bsdf;
        let sample = !ends_after_light(settings, depth);
        let (d, g) = (&mut self.diffuse, &mut self.glossy);
        match (light, sample) {
            (true, true) => map::<true, true>(d, g, mis),
            (true, false) => map::<true, false>(d, g, mis),
            (false, _) => {
                // Under BSDF sampling no path ends after a light sample.
                debug_assert!(sample);
                map::<false, true>(d, g, mis);
            }
        }
    }

    /// The paths `begun` (in the order their rows went in) with their
    /// rows in and out.
    pub fn out<'a>(&'a self, begun: &'a [Begun]) -> RowsOut<'a> {
        debug_assert_eq!(begun.len(), self.diffuse.out.len() + self.glossy.out.len());
        RowsOut {
            begun: begun.iter(),
            diffuse: self.diffuse.rows.iter().zip(&self.diffuse.out),
            glossy: self.glossy.rows.iter().zip(&self.glossy.out),
        }
    }
}

/// A group's rows in with their rows out.
type Group<'a> =
    std::iter::Zip<std::slice::Iter<'a, [f32; BSDF_IN]>, std::slice::Iter<'a, [f32; BSDF_OUT]>>;

/// The paths of a bounce with their rows in and out of [`KernelRows`],
/// path after path.
pub(super) struct RowsOut<'a> {
    begun: std::slice::Iter<'a, Begun>,
    diffuse: Group<'a>,
    glossy: Group<'a>,
}

impl<'a> Iterator for RowsOut<'a> {
    type Item = (&'a Begun, (&'a [f32; BSDF_IN], &'a [f32; BSDF_OUT]));

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        let begun = self.begun.next()?;
        let out = if begun.diffuse {
            self.diffuse.next()
        } else {
            self.glossy.next()
        };
        Some((begun, out?))
    }
}

/// What shading a path's vertex needs besides the path.
pub(super) struct Bounce<'a> {
    pub scene: &'a Scene,
    pub settings: &'a Settings,
}

impl Bounce<'_> {
    /// The emission of the vertex where `path.ray` meets the scene (at
    /// distance `t`, on `shape` at `sp`), added to `l`: `β L_e w`, with the
    /// MIS weight `w` against emitter sampling ([`emission_weight`]).
    #[inline]
    pub fn emit(
        &self,
        path: &Path,
        (t, (shape, sp)): (f32, (u32, &SurfacePoint)),
        l: &mut [f32; 3],
    ) {
        let (scene, settings) = (self.scene, self.settings);
        let ray = path.ray;
        if let Some(le) = scene.emitted(shape, sp.ng, -ray.d) {
            let w = emission_weight(settings, path.depth, path.bsdf_pdf, || {
                scene.light_pdf(shape, path.from, sp.ng, ray.d, t)
            });
            add_scaled(l, path.beta, le, w);
        }
    }

    /// The first step of shading the vertex where `path.ray` meets `shape`
    /// at `sp`, past its emission ([`Bounce::emit`]), where the path goes
    /// on: what [`Bounce::finish`] needs of it (`k`: the path's index at
    /// the bounce's start) and its row of [`bsdf_kernel`], with its light
    /// sample `ls` (which [`KernelRows::set_light`] may also write later)
    /// and its BSDF sample's numbers `bsdf_numbers` (`u`, then the part's;
    /// its frame as `sampler` wants it: [`turns_with_azimuth`]). The
    /// returned [`Begun::row`] is 0, for the caller to set from
    /// [`KernelRows::push`]; the caller keeps the point of an area light's
    /// sample ([`Begun::to_point`]).
    #[inline]
    pub fn begin(
        &self,
        (k, path): (usize, &Path),
        (shape, sp): (u32, &SurfacePoint),
        (ls, bsdf_numbers): (Option<&LightSample>, ([f32; 2], f32)),
        sampler: Sampler,
    ) -> (Begun, [f32; BSDF_IN]) {
        let (scene, settings) = (self.scene, self.settings);
        let wi = -path.ray.d;
        let normal = (
            facing_normal(scene, shape, sp.ns, wi).to_array(),
            turns_with_azimuth(scene, shape, sampler),
        );
        let light = ls
            .filter(|_| settings.strategy != Strategy::Bsdf)
            .map(light_of);
        let row = bsdf_row(
            (normal, wi.to_array()),
            light,
            bsdf_numbers,
            scene.view_terms(shape),
        );
        let begun = Begun {
            k: k as u32,
            row: 0,
            ends: ends_after_light(settings, path.depth),
            diffuse: !scene.material(shape).bsdf.is_glossy(),
            to_point: ls.and_then(LightSample::end).is_some(),
        };
        (begun, row)
    }

    /// The last step of shading a path's vertex (at `sp`, begun as
    /// `begun`, with its kernel's rows in and out): its light sample
    /// connected (its light kept in `shadows` with its shadow ray, toward
    /// the row's direction and up to `point` on an area light, when the
    /// kernel says to connect it), and the path moved on along its BSDF
    /// sample, after roulette (whose number `roulette` draws for the path
    /// and a dimension). The path's next ray when it goes on (also its
    /// `ray`: handed back by value, as the caller stores it too, because
    /// reading it back from the path would wait on the stores that just
    /// wrote it).
    #[inline]
    pub fn finish(
        &self,
        path: &mut Path,
        (begun, sp, (row, out)): (&Begun, &SurfacePoint, (&[f32; BSDF_IN], &[f32; BSDF_OUT])),
        point: Option<&SurfacePoint>,
        (shadows, shadow_rays): (&mut Vec<Unshadowed>, &mut Vec<Ray>),
        roulette: impl FnOnce(&mut Path, u32) -> f32,
    ) -> Option<Ray> {
        let settings = self.settings;
        let [c0, c1, c2, scale, lit, x, y, z, pdf, r, g, b] = *out;
        if lit > 0.0 {
            shadows.push(Unshadowed {
                slot: path.slot,
                time: path.time,
                beta: path.beta,
                fc: [c0, c1, c2],
                s: scale,
            });
            shadow_rays.push(shadow_ray(sp.p, sp.ng, light_direction(row), point));
        }
        if begun.ends || [r, g, b].iter().all(|&v| v <= 0.0) {
            return None;
        }
        let depth = path.depth;
        path.beta = mul(path.beta, [r, g, b]);
        path.bsdf_pdf = pdf;
        let d = Vec3A::new(x, y, z);
        path.from = sp.p;
        let ray = Ray {
            o: offset(sp.p, sp.ng, d),
            d,
            tmax: f32::INFINITY,
        };
        path.ray = ray;
        path.depth += 1;
        if settings.integrator == Integrator::Path && path.depth >= settings.rr_depth {
            let q = path.beta.iter().copied().fold(0.0f32, f32::max).min(0.95);
            if roulette(path, dims::bounce(depth, dims::ROULETTE)) >= q {
                return None;
            }
            path.beta = path.beta.map(|b| b / q);
        }
        Some(ray)
    }
}
