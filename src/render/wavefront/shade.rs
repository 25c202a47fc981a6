//! The shading of a bounce's paths, in three steps over the whole bounce:
//!
//! ```text
//! begin   each path at its hit: its emission, its shading frame, and
//!         its row of the BSDF kernel (the view's wi, the light sample's
//!         direction, the BSDF sample's numbers, the BRDF's terms)
//! kernel  every row at SIMD width (bsdf_kernel): the BRDF and its
//!         density toward the light sample, and the BSDF sample
//! finish  each path: its light sample's light kept with its shadow ray,
//!         its next ray, roulette
//! ```
//!
//! The kernel holds what costs most per vertex (three powers, two sines
//! and cosines, the mirror's frame), which one path at a time would
//! compute in scalar code. It computes both parts' directions and selects,
//! where one path at a time draws only the chosen part's direction: the
//! same bits (`PhongView::eval_pdf_one`, `PhongView::sample_one`). The
//! rows of BRDFs without a glossy part (diffuse surfaces) go to a kernel
//! of their own, without the lobe and the glossy direction (one sine and
//! cosine, no power): the same bits again
//! (`PhongView::eval_pdf_diffuse`, `PhongView::sample_diffuse`).

use glam::Vec3A;

use super::{Path, Unshadowed};
use crate::error::Result;
use crate::frame::Frame;
use crate::math::V3;
use crate::phong::{PhongView, VIEW_TERMS};
use crate::render::integrator::{
    Integrator, Settings, Strategy, add_scaled, dims, emission_weight, ends_after_light, mul,
    offset, shading_frame, shadow_ray,
};
use crate::render::numbers::Numbers;
use crate::render::scene::{LightSample, Scene};
use crate::render::shape::{Ray, SurfacePoint};
use crate::simd;

/// Numbers per row into [`bsdf_kernel`]: `wi` in the shading frame (3),
/// the light sample's direction there (3, zeros without one), the BSDF
/// sample's numbers `u0, u1, part` (3) and the BRDF's
/// [`crate::phong::Phong::view_terms`].
pub(super) const BSDF_IN: usize = 9 + VIEW_TERMS;

/// Numbers per row out of [`bsdf_kernel`]: `f_r` toward the light sample
/// (3) and the BSDF's density there, then the BSDF sample's direction (3),
/// density and weight (3).
pub(super) const BSDF_OUT: usize = 11;

/// What [`Bounce::finish`] needs of a path's [`Bounce::begin`].
#[derive(Clone, Copy, Debug)]
pub(super) struct Begun {
    /// The path's index at the bounce's start (of its surface, light
    /// sample and numbers drawn beforehand).
    pub k: u32,
    /// Its shading frame.
    pub frame: Frame<f32>,
    /// The cosine of its light sample's direction with the shading
    /// normal (0 without one).
    pub wl_z: f32,
    /// Whether it ends after its light sample (emitter sampling, whose
    /// next vertex's emission would not count).
    pub ends: bool,
    /// Whether its BRDF has no glossy part (`ρs = 0`: its row goes to
    /// the kernel without the lobe, [`KernelRows`]).
    pub diffuse: bool,
}

/// The row of [`BSDF_IN`] numbers of [`bsdf_kernel`] for the view from
/// `wi` of the BRDF of `terms`, the light sample's direction `wl` and the
/// BSDF sample's numbers `u` and `part` (all in the shading frame).
#[inline]
pub(super) fn bsdf_row(
    (wi, wl): (V3<f32>, V3<f32>),
    (u, part): ([f32; 2], f32),
    terms: &[f32; VIEW_TERMS],
) -> [f32; BSDF_IN] {
    let mut row = [0.0; BSDF_IN];
    row[..3].copy_from_slice(&wi);
    row[3..6].copy_from_slice(&wl);
    row[6..9].copy_from_slice(&[u[0], u[1], part]);
    row[9..].copy_from_slice(terms);
    row
}

/// The BSDF's part of a vertex's shading, for one row of [`BSDF_IN`]
/// numbers ([`bsdf_row`]): with `LIGHT`, `(f_r(wi, wl), p(wl))` toward
/// the light sample's direction `wl` ([`PhongView::eval_pdf`]); with
/// `SAMPLE`, the sample [`PhongView::sample`] of `[u0, u1, part]`; as
/// [`BSDF_OUT`] numbers (zeros for the part not asked for: under BSDF
/// sampling the light's power is skipped, and where every path ends
/// after its light sample, the sample's two). `GLOSSY` is the general
/// kernel, right for every row; without it, for rows of BRDFs without a
/// glossy part only, by their diffuse forms (no lobe: the same bits,
/// [`PhongView::eval_pdf_diffuse`], [`PhongView::sample_diffuse`]).
/// Branch-free, for [`crate::simd::map_rows`].
#[inline(always)]
pub(super) fn bsdf_kernel<const LIGHT: bool, const SAMPLE: bool, const GLOSSY: bool>(
    row: [f32; BSDF_IN],
) -> [f32; BSDF_OUT] {
    let [w0, w1, w2, l0, l1, l2, u0, u1, part, terms @ ..] = row;
    let view = PhongView::from_terms([w0, w1, w2], terms);
    let ([f0, f1, f2], pdf_l) = match (LIGHT, GLOSSY) {
        (false, _) => ([0.0; 3], 0.0),
        (true, true) => view.eval_pdf([l0, l1, l2]),
        (true, false) => view.eval_pdf_diffuse([l0, l1, l2]),
    };
    let ([x, y, z], pdf, [r, g, b]) = if SAMPLE {
        let s = if GLOSSY {
            view.sample([u0, u1, part])
        } else {
            view.sample_diffuse([u0, u1])
        };
        (s.wo, s.pdf, s.weight)
    } else {
        ([0.0; 3], 0.0, [0.0; 3])
    };
    [f0, f1, f2, pdf_l, x, y, z, pdf, r, g, b]
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

    /// The row of the next path, in the diffuse group or not.
    #[inline]
    pub fn push(&mut self, diffuse: bool, row: [f32; BSDF_IN]) {
        let group = if diffuse {
            &mut self.diffuse
        } else {
            &mut self.glossy
        };
        group.rows.push(row);
    }

    /// [`bsdf_kernel`] of every row, for a bounce of `settings` at
    /// `depth`: the light's part where the strategy draws light samples,
    /// the BSDF sample's where the paths go on after them.
    pub fn run(&mut self, settings: &Settings, depth: u32) {
        fn map<const LIGHT: bool, const SAMPLE: bool>(d: &mut Rows, g: &mut Rows) {
            fn one<const LIGHT: bool, const SAMPLE: bool, const GLOSSY: bool>(group: &mut Rows) {
                // Through a closure marked inline: given the function
                // itself, the kernel ran 50 % slower (demo BSDF sampling
                // 20.4 -> 30.6 ms).
                let kernel = {
                    #[inline(always)]
                    |row| bsdf_kernel::<LIGHT, SAMPLE, GLOSSY>(row)
                };
                group.out.clear();
                group.out.resize(group.rows.len(), [0.0; BSDF_OUT]);
                simd::map_rows(&mut group.out, &group.rows, &kernel, |_| true, false);
            }
            one::<LIGHT, SAMPLE, false>(d);
            one::<LIGHT, SAMPLE, true>(g);
        }
        let light = settings.strategy != Strategy::Bsdf;
        let sample = !ends_after_light(settings, depth);
        let (d, g) = (&mut self.diffuse, &mut self.glossy);
        match (light, sample) {
            (true, true) => map::<true, true>(d, g),
            (true, false) => map::<true, false>(d, g),
            (false, _) => {
                // Under BSDF sampling no path ends after a light sample.
                debug_assert!(sample);
                map::<false, true>(d, g);
            }
        }
    }

    /// The paths `begun` (in the order their rows went in) with their
    /// rows out.
    pub fn out<'a>(&'a self, begun: &'a [Begun]) -> RowsOut<'a> {
        debug_assert_eq!(begun.len(), self.diffuse.out.len() + self.glossy.out.len());
        RowsOut {
            begun: begun.iter(),
            diffuse: self.diffuse.out.iter(),
            glossy: self.glossy.out.iter(),
        }
    }
}

/// The paths of a bounce with their rows out of [`KernelRows`], path
/// after path.
pub(super) struct RowsOut<'a> {
    begun: std::slice::Iter<'a, Begun>,
    diffuse: std::slice::Iter<'a, [f32; BSDF_OUT]>,
    glossy: std::slice::Iter<'a, [f32; BSDF_OUT]>,
}

impl<'a> Iterator for RowsOut<'a> {
    type Item = (&'a Begun, &'a [f32; BSDF_OUT]);

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
    /// The first step of shading the vertex where `path.ray` meets the
    /// scene (at distance `t`, on `shape` at `sp`), whose light sample is
    /// `ls`: its emission added to `l`; `None` if the path ends there,
    /// else what [`Bounce::finish`] needs of it (`k`: the path's index at
    /// the bounce's start) and its row of [`bsdf_kernel`] (the BSDF
    /// sample's numbers drawn from `numbers`, unless the path ends after
    /// its light sample).
    #[inline]
    pub fn begin(
        &self,
        (k, path): (usize, &Path),
        (t, (shape, sp)): (f32, (u32, &SurfacePoint)),
        ls: Option<&LightSample>,
        numbers: &mut Numbers,
        l: &mut [f32; 3],
    ) -> Option<(Begun, [f32; BSDF_IN])> {
        let (scene, settings) = (self.scene, self.settings);
        let (ray, depth) = (path.ray, path.depth);
        let wi = -ray.d;
        if let Some(le) = scene.emitted(shape, sp.ng, wi) {
            let w = emission_weight(settings, depth, path.bsdf_pdf, || {
                scene.light_pdf(shape, path.from, sp.ng, ray.d, t)
            });
            add_scaled(l, path.beta, le, w);
        }
        let max_depth = settings.max_depth();
        if depth + 1 >= max_depth {
            return None;
        }
        let frame = shading_frame(scene, shape, sp.ns, wi, numbers.stream.sampler());
        let wl = match ls {
            Some(ls) if settings.strategy != Strategy::Bsdf => frame.to_local(ls.d.to_array()),
            _ => [0.0; 3],
        };
        let ends = ends_after_light(settings, depth);
        // The direction from the 2D request, the part from the 1D one
        // (drawn in this order, the independent sampler's numbers are
        // those of `PhongView::sample`'s `[u0, u1, part]`).
        let bsdf_numbers = if ends {
            ([0.0; 2], 0.0)
        } else {
            let u = numbers.get2(dims::bounce(depth, dims::BSDF_DIRECTION));
            (u, numbers.get1(dims::bounce(depth, dims::BSDF_COMPONENT)))
        };
        let wi_local = frame.to_local(wi.to_array());
        let bsdf = &scene.material(shape).bsdf;
        let row = bsdf_row((wi_local, wl), bsdf_numbers, &bsdf.view_terms());
        let begun = Begun {
            k: k as u32,
            frame,
            wl_z: wl[2],
            ends,
            diffuse: !bsdf.is_glossy(),
        };
        Some((begun, row))
    }

    /// The light sample `ls` seen from the shading point `sp` of `path`,
    /// where the cosine of its direction is `wl_z`, the BRDF toward it `f`
    /// and its density `pdf_wl` (the kernel's): its light (BSDF, cosine,
    /// MIS weight) kept in `shadows` with its shadow ray when it carries
    /// any.
    #[inline]
    fn connect(
        &self,
        path: &Path,
        sp: &SurfacePoint,
        (wl_z, f, pdf_wl): (f32, [f32; 3], f32),
        ls: &LightSample,
        (shadows, shadow_rays): (&mut Vec<Unshadowed>, &mut Vec<Ray>),
    ) {
        if f.iter().any(|&v| v > 0.0) {
            let w = if self.settings.strategy == Strategy::Mis {
                self.settings.weight(ls.pdf, pdf_wl)
            } else {
                1.0
            };
            shadows.push(Unshadowed {
                slot: path.slot,
                time: path.time,
                beta: path.beta,
                fc: mul(f, ls.radiance),
                s: w * wl_z.abs() / ls.pdf,
            });
            shadow_rays.push(shadow_ray(sp.p, sp.ng, ls));
        }
    }

    /// The last step of shading a path's vertex (at `sp`, begun as
    /// `begun`, with the kernel's numbers `out`): its light sample `ls`
    /// connected, and the path moved on along its BSDF sample, after
    /// roulette (whose number `roulette` draws for the path and a
    /// dimension). The path's next ray when it goes on (also its
    /// `ray`: handed back by value, as the caller stores it too,
    /// because reading it back from the path would wait on the stores
    /// that just wrote it).
    #[inline]
    pub fn finish(
        &self,
        path: &mut Path,
        (begun, sp, out): (&Begun, &SurfacePoint, &[f32; BSDF_OUT]),
        ls: Option<&LightSample>,
        shadows: (&mut Vec<Unshadowed>, &mut Vec<Ray>),
        roulette: impl FnOnce(&mut Path, u32) -> f32,
    ) -> Option<Ray> {
        let settings = self.settings;
        let [f0, f1, f2, pdf_wl, x, y, z, pdf, r, g, b] = *out;
        if settings.strategy != Strategy::Bsdf
            && let Some(ls) = ls
        {
            self.connect(path, sp, (begun.wl_z, [f0, f1, f2], pdf_wl), ls, shadows);
        }
        if begun.ends || [r, g, b].iter().all(|&v| v <= 0.0) {
            return None;
        }
        let depth = path.depth;
        path.beta = mul(path.beta, [r, g, b]);
        path.bsdf_pdf = pdf;
        let d = Vec3A::from(begun.frame.to_world([x, y, z])).normalize();
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
