//! Where a sample's numbers come from. The camera's are drawn for a whole
//! batch of samples beforehand, at SIMD width, and read by position
//! ([`camera_dims`], [`camera_values`]): under the independent sampler as
//! the first draws of each sample's own generator. The shading's are
//! [`Numbers`]: the independent sampler's drawn as the shading asks for
//! them (their order is their meaning); the other samplers' depend only on
//! the sample and the dimension, so the requests a bounce of a batch's
//! paths will make are drawn for the whole batch beforehand
//! ([`crate::sampler::batch`]), and then read.

use super::integrator::{Integrator, Settings, Strategy, dims, ends_after_light};
use crate::rng::Rng;
use crate::sampler::batch::Dim;
use crate::sampler::{Sampler, Stream};

/// The numbers of one path's bounce.
pub struct Numbers<'a> {
    /// The pixel's stream, at the sample.
    pub stream: &'a mut Stream,
    /// The dimensions drawn for every sample of the step beforehand, and
    /// this sample's values of them.
    drawn: (&'a [Dim], &'a [[f32; 2]]),
}

impl<'a> Numbers<'a> {
    /// The numbers of sample `k` of a step whose samples were each drawn
    /// `dims` beforehand (`values`, sample after sample); none when out of
    /// bounds: then all are asked of the stream.
    pub fn new(
        stream: &'a mut Stream,
        (dims, values): (&'a [Dim], &'a [[f32; 2]]),
        k: usize,
    ) -> Self {
        let d = dims.len();
        let mine = values.get(k * d..(k + 1) * d);
        Numbers {
            stream,
            drawn: mine.map_or((&[], &[]), |v| (dims, v)),
        }
    }

    /// Coordinate `dim` of the sample ([`Stream::get1`]).
    #[inline]
    pub fn get1(&mut self, dim: u32) -> f32 {
        self.find(dim, false)
            .map_or_else(|| self.stream.get1(dim), |v| v[0])
    }

    /// Coordinates `dim` and `dim + 1` ([`Stream::get2`]).
    #[inline]
    pub fn get2(&mut self, dim: u32) -> [f32; 2] {
        self.find(dim, true)
            .unwrap_or_else(|| self.stream.get2(dim))
    }

    /// [`Stream::independent`].
    #[inline]
    pub fn independent(&mut self) -> Option<&mut Rng> {
        self.stream.independent()
    }

    /// The value drawn beforehand for the 1D or 2D (`two`) request of
    /// `dim`, if it was. A request that [`bounce_dims`] did not foresee
    /// is asked of the stream: the same bits, only slower;
    /// debug builds check that none is missed.
    #[inline]
    fn find(&self, dim: u32, two: bool) -> Option<[f32; 2]> {
        let (dims, values) = self.drawn;
        let found = dims.iter().position(|&d| d == Dim { dim, two });
        debug_assert!(
            dims.is_empty() || found.is_some(),
            "dimension {dim} not drawn"
        );
        values.get(found?).copied()
    }
}

/// The dimensions the camera asks each sample for (`Batch::run`, in its
/// order): the film position, the lens position when the camera has a
/// lens, the time when something moves.
pub fn camera_dims((lens, time): (bool, bool)) -> Vec<Dim> {
    let mut out = vec![Dim {
        dim: dims::FILM,
        two: true,
    }];
    if lens {
        out.push(Dim {
            dim: dims::LENS,
            two: true,
        });
    }
    if time {
        out.push(Dim {
            dim: dims::TIME,
            two: false,
        });
    }
    out
}

/// One sample's film position, lens position (`[0.5; 2]` when not drawn)
/// and time (0 when not drawn), from its values of
/// [`camera_dims`]`((lens, time))`, in their order.
#[inline(always)]
pub fn camera_values(values: &[[f32; 2]], (lens, time): (bool, bool)) -> ([f32; 2], [f32; 2], f32) {
    let lens_u = if lens { values[1] } else { [0.5; 2] };
    let t = if time {
        values[1 + usize::from(lens)][0]
    } else {
        0.0
    };
    (values[0], lens_u, t)
}

/// Whether the shading draws the light's choice: when the scene has more
/// than one light (`many_lights`), and always under the independent
/// sampler, whose draws keep their order (the others' numbers depend only
/// on the dimension, and a choice among one light reads none).
#[inline]
pub fn draws_light_choice(many_lights: bool, sampler: Sampler) -> bool {
    many_lights || sampler == Sampler::Independent
}

/// The dimensions the shading of each path's vertex at `depth` asks for
/// (its light sample's, then its BSDF sample's, both in
/// `Wavefront::begin_vertices`, then its roulette's in `Bounce::finish`, in
/// this order: [`super::wavefront`]) under a sampler
/// other than the independent one, into `out`: none at the last vertex;
/// the light's choice (when `many_lights`, [`draws_light_choice`]) and
/// position unless only the BSDF is sampled; the BSDF's direction and
/// component unless emitter sampling stops there; Russian roulette from
/// `rr_depth` on (path integrator).
pub fn bounce_dims(settings: &Settings, many_lights: bool, depth: u32, out: &mut Vec<Dim>) {
    out.clear();
    let max_depth = settings.max_depth();
    if depth + 1 >= max_depth {
        return;
    }
    let mut push = |offset: u32, two: bool| {
        out.push(Dim {
            dim: dims::bounce(depth, offset),
            two,
        });
    };
    if settings.strategy != Strategy::Bsdf {
        if many_lights {
            push(dims::LIGHT_CHOICE, false);
        }
        push(dims::LIGHT_POSITION, true);
        if ends_after_light(settings, depth) {
            return;
        }
    }
    push(dims::BSDF_DIRECTION, true);
    push(dims::BSDF_COMPONENT, false);
    if settings.integrator == Integrator::Path && depth + 1 >= settings.rr_depth {
        push(dims::ROULETTE, false);
    }
}
