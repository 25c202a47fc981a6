//! [`Weights`]: the weights of a 1D table as given and their sum, which
//! the CDF table and the alias table both keep to answer `pmf` (each
//! dereferences to it).

use crate::buffer::Buffer;

/// The weights `w_i` of a 1D table and their sum `Σw` (accumulated in
/// `f64`).
///
/// # Probability
/// `P(i) = w_i / Σw`, 0 outside the table.
#[derive(Clone, Debug)]
pub struct Weights {
    values: Buffer<f64>,
    sum: f64,
}

impl Weights {
    /// Weights already checked (finite, `>= 0`) and their sum.
    pub(crate) fn new(values: Buffer<f64>, sum: f64) -> Self {
        Weights { values, sum }
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether the table has no entries (never true for a built table).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The sum of the weights (the normalisation constant).
    pub fn sum(&self) -> f64 {
        self.sum
    }

    /// The weight of entry `i` as given (0 outside the table).
    pub fn weight(&self, i: usize) -> f64 {
        self.values.get(i).copied().unwrap_or(0.0)
    }

    /// The weights as given.
    pub fn weights(&self) -> &[f64] {
        &self.values
    }

    /// Probability of index `i`: `w_i / Σw` (0 outside the table).
    pub fn pmf(&self, i: usize) -> f64 {
        self.weight(i) / self.sum
    }
}
