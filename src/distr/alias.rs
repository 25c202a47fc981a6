//! [`AliasTable`]: O(1) sampling of a discrete distribution (Walker's alias
//! method, built by sweeping).

use super::check_weights;
use crate::buffer::Buffer;
use crate::error::{Error, Result};
use crate::math::Real;

/// A discrete distribution over `0..n` with probabilities proportional to
/// non-negative weights, sampled in O(1) with one uniform number.
///
/// # Probability
/// `P(i) = w_i / Σw`, the same as [`super::Discrete1D`] (a different map
/// from `u` to indices).
///
/// # Sampling
/// With `t = u·n`, cell `c = ⌊t⌋` keeps its own index when `t − c` is below
/// the cell's threshold, and otherwise returns the cell's alias. Every cell
/// holds mass `1/n`: its own share `w_c·n/Σw`, topped up from one donor.
/// An entry of weight 0 has threshold 0 and is never returned.
///
/// # References
/// M. D. Vose, "A linear algorithm for generating random numbers with a
/// given distribution", IEEE Transactions on Software Engineering 17(9),
/// 1991. L. Hübschle-Schneider, P. Sanders, "Parallel Weighted Random
/// Sampling", ACM Transactions on Mathematical Software 48(3), 2022 (the
/// sweeping construction used here).
#[derive(Clone, Debug)]
pub struct AliasTable {
    /// Cell `c` keeps its own index when the fractional part of `u·n` is
    /// below its threshold, else returns its alias: `[threshold bits,
    /// alias]` side by side, so a draw touches one cache line.
    cells: Buffer<[u64; 2]>,
    pmf: Buffer<f64>,
    sum: f64,
}

impl AliasTable {
    /// An alias table proportional to `weights`.
    ///
    /// # Errors
    /// As [`super::Discrete1D::new`].
    pub fn new(weights: &[f64]) -> Result<Self> {
        check_weights("weights", weights, |i| format!("[{i}]"))?;
        let sum: f64 = weights.iter().sum();
        if !(sum > 0.0 && sum.is_finite()) {
            return Err(Error::AllZero { arg: "weights" });
        }
        let n = weights.len();
        let mut pmf = Buffer::zeroed(n);
        for (p, &w) in pmf.iter_mut().zip(weights) {
            *p = w / sum;
        }
        let share = |i: usize| pmf[i] * n as f64;

        // Entries below their 1/n share ("light") in increasing order from
        // the front of `order`, the others ("heavy") from the back, written
        // branch-free (the order of the weights is random to the predictor).
        let mut order = Buffer::<u32>::zeroed(n);
        let (mut n_light, mut n_heavy) = (0usize, 0usize);
        for i in 0..n {
            let light = (share(i) < 1.0) as usize;
            order[n_light] = i as u32;
            order[n - 1 - n_heavy] = i as u32;
            n_light += light;
            n_heavy += 1 - light;
        }
        let light = |k: usize| order[k] as usize;
        let heavy = |k: usize| order[n - 1 - k] as usize;

        // Sweep (Hübschle-Schneider and Sanders): the current heavy entry
        // tops up light entries in order while its residual `w` exceeds one
        // share; once it drops to one share or less it is itself a light
        // cell, topped up by the next heavy entry. Both cursors only move
        // forward, and each step is a select, not a branch.
        let mut cells = Buffer::<[u64; 2]>::zeroed(n);
        let (mut i, mut j) = (0usize, 0usize);
        let mut w = if n_heavy > 0 { share(heavy(0)) } else { 0.0 };
        while n_heavy > 0 && (i < n_light || j + 1 < n_heavy) {
            let can_light = i < n_light;
            let can_heavy = j + 1 < n_heavy;
            let light_step = can_light & ((w > 1.0) | !can_heavy);
            let l = light(i.min(n_light.saturating_sub(1)));
            let next = heavy((j + 1).min(n_heavy - 1));
            let (cell, threshold, alias) = if light_step {
                (l, share(l), heavy(j))
            } else {
                (heavy(j), w, next)
            };
            cells[cell] = [threshold.to_bits(), alias as u64];
            w = if light_step {
                w + share(l) - 1.0
            } else {
                share(next) + w - 1.0
            };
            i += light_step as usize;
            j += (!light_step) as usize;
        }
        // What is left holds (up to round-off) exactly one share each: the
        // last heavy entry and any light entries. An entry of weight 0 left
        // over points at the most likely entry instead.
        let donor = (0..n).fold(0, |best, k| if pmf[k] > pmf[best] { k } else { best });
        let rest = (i..n_light).map(light).chain((j..n_heavy).map(heavy));
        for k in rest {
            cells[k] = if pmf[k] > 0.0 {
                [1.0f64.to_bits(), k as u64]
            } else {
                [0.0f64.to_bits(), donor as u64]
            };
        }
        Ok(AliasTable { cells, pmf, sum })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// Whether the table has no entries (never true for a built table).
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// The sum of the weights.
    pub fn sum(&self) -> f64 {
        self.sum
    }

    /// Probability of index `i`: `w_i / Σw` (0 outside the table).
    pub fn pmf(&self, i: usize) -> f64 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// An index drawn with probability `pmf(i)`; `u` in `[0, 1]`.
    #[inline]
    pub fn sample<F: Real>(&self, u: F) -> usize {
        let n = self.pmf.len();
        let t = u.f64() * n as f64;
        let c = (t as usize).min(n - 1);
        let [threshold, alias] = self.cells[c];
        // A select, not a branch: the outcome is random, and a mispredicted
        // branch would stall the other draws' memory loads.
        let keep = t - (c as f64) < f64::from_bits(threshold);
        if keep { c } else { alias as usize }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The probability of each index, read off the table: each cell gives
    /// `threshold/n` to itself and the rest to its alias.
    fn table_pmf(t: &AliasTable) -> Vec<f64> {
        let n = t.len();
        let mut p = vec![0.0; n];
        for i in 0..n {
            let [threshold, alias] = t.cells[i];
            let keep = f64::from_bits(threshold).min(1.0);
            p[i] += keep / n as f64;
            p[alias as usize] += (1.0 - keep) / n as f64;
        }
        p
    }

    #[test]
    fn table_realises_the_pmf() {
        let w = [0.0, 1.0, 0.0, 2.0, 3.0, 0.0, 10.0];
        let t = AliasTable::new(&w).unwrap();
        for (i, p) in table_pmf(&t).into_iter().enumerate() {
            assert!((p - w[i] / 16.0).abs() < 1e-12, "index {i}: {p}");
        }
        assert_eq!(t.sample(1.0), t.sample(f64::ONE_MINUS_EPSILON));
    }

    #[test]
    fn errors() {
        assert!(AliasTable::new(&[]).is_err());
        assert!(AliasTable::new(&[0.0]).is_err());
        assert!(AliasTable::new(&[1.0, f64::INFINITY]).is_err());
    }

    proptest! {
        #[test]
        fn never_returns_a_zero_weight_and_keeps_the_pmf(
            weights in prop::collection::vec(prop_oneof![Just(0.0), 0.0..10.0f64, 1e-300..1e-290f64], 1..500),
            us in prop::collection::vec(0.0..=1.0f64, 50),
        ) {
            if let Ok(t) = AliasTable::new(&weights) {
                for u in us.into_iter().chain([0.0, 1.0]) {
                    let i = t.sample(u);
                    prop_assert!(weights[i] > 0.0, "u = {} gave zero-weight index {}", u, i);
                }
                for (i, p) in table_pmf(&t).into_iter().enumerate() {
                    prop_assert!((p - t.pmf(i)).abs() < 1e-9, "index {}: {} vs {}", i, p, t.pmf(i));
                }
            }
        }
    }
}
