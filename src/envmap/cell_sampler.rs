//! [`CellSampler`]: draws from an environment map's luminance or piecewise
//! density in O(1), for renderers' light samples (one at a time, or a
//! bounce's together: [`CellSampler::sample_many`]).

use super::distribution::Distribution;
use super::polar::TableFloat;
use super::{EnvMap, EnvSample};
use crate::distr::AliasTable;
use crate::error::Result;
use crate::simd;

/// The density of [`EnvMap::sample`] (luminance or piecewise sampling),
/// drawn in O(1): the table cell `(row, col)` by an [`AliasTable`] over the
/// cells' weights, the point within it by two numbers of its own, as
/// [`EnvMap::sample`] places it in the cell.
///
/// # Density
/// That of [`EnvMap::pdf`]: cell `c` is drawn with probability `w_c/Σw`
/// (to the alias table's 32-bit thresholds) and its point by the cell's
/// own density (uniform in a piecewise table's cell, bilinear in a
/// luminance density's), which is the table density `p_q`, `p_q / (dω/dp)`
/// per steradian. The map from numbers to directions differs from
/// [`EnvMap::sample`]'s inversion (no `sample_reuse`, no inverse): one
/// draw costs a load of the cell and no search, which matters where draws
/// come between other work (a renderer's next-event estimation), and the
/// cache misses of a search's loads, each waiting on the last, could not
/// overlap.
#[derive(Clone, Debug)]
pub struct CellSampler {
    cells: AliasTable,
    cols: usize,
}

impl CellSampler {
    /// The sampler of `env`'s cells, or `None` when `env` is sampled by
    /// neither the luminance density nor a piecewise table (Mitsuba's
    /// bilinear density, or an all-black map).
    ///
    /// # Errors
    /// Only when the thread pool cannot start.
    pub fn new(env: &EnvMap) -> Result<Option<Self>> {
        let table = match &env.distribution {
            Distribution::Luminance(density) => density.cells(),
            Distribution::Piecewise(table) => table.table(),
            Distribution::Bilinear(_) | Distribution::Black => return Ok(None),
        };
        Ok(Some(CellSampler {
            cells: AliasTable::new(table.weights())?,
            cols: table.shape().1,
        }))
    }

    /// A direction of `env` (the map this sampler was built for) as an
    /// [`EnvSample`]; its `radiance` is what a renderer's light sample
    /// wants. The cell comes from the 64 random bits `bits`, the point
    /// within it from the fractions `r` in `[0, 1)²` (along the table's x
    /// and y); from there it is the path of [`EnvMap::sample`]. Computed in
    /// `F`: in `f32` the point stays in its cell, placed from the `f32`
    /// tables as [`EnvMap::sample_into`] places it, and the direction and
    /// density are good to a few `f32` ulps. (Given a map that has no
    /// cells, it draws by [`EnvMap::sample`] of `r`.)
    #[inline]
    pub fn sample<F: TableFloat>(&self, env: &EnvMap, bits: u64, r: [F; 2]) -> EnvSample<F> {
        let cell = self.cell(bits);
        let placed = match &env.distribution {
            Distribution::Luminance(density) => env.place_luminance(density, cell, r),
            Distribution::Piecewise(table) => env.place_in_cell(table, cell, r),
            Distribution::Bilinear(_) | Distribution::Black => {
                return env.sample(r.map(F::f64)).cast();
            }
        };
        env.sample_at(&placed)
    }

    /// The table cell `(row, col)` drawn from the 64 bits `bits`.
    #[inline(always)]
    pub(super) fn cell(&self, bits: u64) -> (usize, usize) {
        let c = self.cells.sample_bits(bits);
        (c / self.cols, c % self.cols)
    }

    /// [`CellSampler::sample`] of each `(bits, r)` of `draws`, appended to
    /// `out` in order, the same samples: drawn together, in groups whose
    /// table reads overlap and whose directions and densities are computed
    /// at SIMD width (as [`EnvMap::sample_into`] draws).
    pub fn sample_many<F: TableFloat>(
        &self,
        env: &EnvMap,
        draws: &[(u64, [F; 2])],
        out: &mut Vec<EnvSample<F>>,
    ) {
        simd::dispatch(
            #[inline(always)]
            |_| env.sample_cells(self, draws, out),
        );
    }
}
