//! Tests of [`super::AliasTable`].

use super::*;
use proptest::prelude::*;

/// The probability of each index, read off the table: each cell gives
/// `threshold/n` to itself and the rest to its alias; and the number of
/// cells that give each index some probability.
fn table_pmf(t: &AliasTable) -> (Vec<f64>, Vec<usize>) {
    let n = t.len();
    let (mut p, mut cells) = (vec![0.0; n], vec![0; n]);
    for i in 0..n {
        let [threshold, alias] = t.cells[i];
        let keep = f64::from(threshold) / ONE;
        p[i] += keep / n as f64;
        p[alias as usize] += (1.0 - keep) / n as f64;
        cells[i] += 1;
        cells[alias as usize] += usize::from(alias as usize != i);
    }
    (p, cells)
}

#[test]
fn table_realises_the_pmf() {
    let w = [0.0, 1.0, 0.0, 2.0, 3.0, 0.0, 10.0];
    let t = AliasTable::new(&w).unwrap();
    for (i, p) in table_pmf(&t).0.into_iter().enumerate() {
        assert!((p - w[i] / 16.0).abs() < 1e-12, "index {i}: {p}");
    }
    assert_eq!(t.sample(1.0), t.sample(f64::ONE_MINUS_EPSILON));
}

/// Draws from evenly spaced 64-bit patterns realise each entry's
/// probability: `M` patterns stratify `[0, 2⁶⁴)`, so each cell's kept
/// and aliased parts receive their share of them to within one pattern.
#[test]
fn bit_draws_realise_the_pmf() {
    let w = [0.0, 1.0, 0.0, 2.0, 3.0, 0.0, 10.0, 0.5];
    let t = AliasTable::new(&w).unwrap();
    let m = 1u64 << 20;
    let mut counts = [0u64; 8];
    for k in 0..m {
        counts[t.sample_bits(k << 44 | (k * 0x9E37) & 0xFFF)] += 1;
    }
    for (i, &c) in counts.iter().enumerate() {
        let expected = t.pmf(i) * m as f64;
        assert!(
            (c as f64 - expected).abs() <= 16.0,
            "index {i}: {c} vs {expected}"
        );
    }
    assert_eq!(t.sample_bits(u64::MAX), t.sample(f64::ONE_MINUS_EPSILON));
    assert_eq!(t.sample_bits(0), t.sample(0.0));
}

/// Asserts that `t` realises its pmf (up to the rounding of each
/// threshold to 32 bits, `2^-32/n` at most in each cell that gives the
/// entry probability) and that batch and single draws agree and never
/// return an entry of weight 0.
fn check_table(t: &AliasTable, w: &[f64]) {
    let n = t.len() as f64;
    let (pmf, cells) = table_pmf(t);
    for (i, (p, cells)) in pmf.into_iter().zip(cells).enumerate() {
        let want = t.pmf(i);
        assert!(
            (p - want).abs() <= 1e-12 * want + cells as f64 / (ONE * n),
            "index {i}: {p} vs {want}"
        );
    }
    let us: Vec<f64> = (0..=100_000).map(|k| k as f64 / 100_000.0).collect();
    let mut batch = vec![0u64; us.len()];
    t.sample_into(&us, &mut batch);
    for (&u, &i) in us.iter().zip(&batch) {
        assert_eq!(i as usize, t.sample(u));
        assert!(w[i as usize] > 0.0, "u = {u} gave zero-weight index {i}");
    }
}

#[test]
fn blocks_built_apart_make_one_table() {
    // Several blocks and a short one, runs of zeros and spikes, so that
    // blocks leave lights or heavies over.
    let w: Vec<f64> = (0..3 * BLOCK + 1234)
        .map(|i| match i % 97 {
            0 => 500.0,
            1..=40 => 0.0,
            k => (k % 13) as f64 * 0.1,
        })
        .collect();
    check_table(&AliasTable::new(&w).unwrap(), &w);
}

#[test]
fn sorted_weights_leave_everything_over() {
    // Blocks of lights only, then of heavies only: the last sweep
    // settles nearly all entries.
    let n = 12 * BLOCK + 77;
    let w: Vec<f64> = (0..n).map(|i| (i / 3) as f64).collect();
    check_table(&AliasTable::new(&w).unwrap(), &w);
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
            for (i, p) in table_pmf(&t).0.into_iter().enumerate() {
                prop_assert!((p - t.pmf(i)).abs() < 1e-9, "index {}: {} vs {}", i, p, t.pmf(i));
            }
        }
    }
}
