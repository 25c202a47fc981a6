//! Quadrature for the tests: integrals over the sphere that check densities
//! integrate to 1 and estimators match their integrands.

use std::f64::consts::TAU;

/// `∫ f(ω) dω` over the unit sphere by the midpoint rule on an `n_phi × n_z`
/// grid in `(φ, cos θ)`, which is area-preserving (each cell is
/// `4π / (n_phi n_z)` steradians); `ω = (r cos φ, r sin φ, z)`.
pub fn integrate_sphere(f: impl Fn([f64; 3]) -> f64, n_phi: usize, n_z: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n_phi {
        let (s, c) = ((i as f64 + 0.5) / n_phi as f64 * TAU).sin_cos();
        for j in 0..n_z {
            let z = -1.0 + (j as f64 + 0.5) / n_z as f64 * 2.0;
            let r = (1.0 - z * z).sqrt();
            sum += f([r * c, r * s, z]);
        }
    }
    sum * 2.0 * TAU / (n_phi * n_z) as f64
}
