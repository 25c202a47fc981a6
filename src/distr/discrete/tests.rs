//! Tests of [`super::Discrete1D`] and its batch search.

use super::*;
use crate::distr::search::{GuideCell, Lanes, fill_guide};
use proptest::prelude::*;

/// The reference: a linear scan for `C_{i−1} < u·Σw ≤ C_i` over the
/// entries of positive weight.
fn linear(table: &Discrete1D, u: f64) -> usize {
    let value = u * table.sum();
    (table.first..=table.last)
        .find(|&i| table.cdf[i] >= value)
        .unwrap_or(table.last)
}

#[test]
fn known_values_as_mitsuba() {
    // Mitsuba 3: DiscreteDistribution([0, 1, 0, 2, 3, 0]).sample(u)
    let d = Discrete1D::new(&[0.0, 1.0, 0.0, 2.0, 3.0, 0.0]).unwrap();
    assert_eq!(d.sample(0.0), 1);
    assert_eq!(d.sample(1.0 / 6.0), 1);
    assert_eq!(d.sample(0.5), 3);
    assert_eq!(d.sample(1.0), 4);
    let (i, r) = d.sample_reuse(0.25f64);
    assert_eq!(i, 3);
    assert!((r - 0.25).abs() < 1e-12, "{r}");
    assert_eq!(d.sum(), 6.0);
    assert_eq!(d.pmf(3), 1.0 / 3.0);
    assert_eq!(d.cdf(5), 1.0);
}

#[test]
fn errors() {
    assert!(matches!(
        Discrete1D::new(&[1.0, -0.5]),
        Err(Error::InvalidWeight { .. })
    ));
    assert!(matches!(
        Discrete1D::new(&[1.0, f64::NAN]),
        Err(Error::InvalidWeight { .. })
    ));
    assert!(matches!(
        Discrete1D::new(&[0.0, 0.0]),
        Err(Error::AllZero { .. })
    ));
    assert!(matches!(Discrete1D::new(&[]), Err(Error::AllZero { .. })));
    // A sum that overflows is no distribution either.
    assert!(Discrete1D::new(&[f64::MAX, f64::MAX]).is_err());
}

#[test]
fn guide_table_agrees_with_a_linear_scan() {
    let n = 5000;
    let weights: Vec<f64> = (0..n)
        .map(|i| {
            if i % 7 == 3 {
                0.0
            } else {
                ((i * 37) % 11) as f64
            }
        })
        .collect();
    let d = Discrete1D::new(&weights).unwrap();
    assert!(!d.guide.is_empty());
    for k in 0..=20_000 {
        let u = k as f64 / 20_000.0;
        assert_eq!(d.sample(u), linear(&d, u), "u = {u}");
    }
    // Exactly on every running sum.
    for i in 0..n {
        let u = d.cdf[i] / d.sum();
        assert_eq!(d.sample(u), linear(&d, u), "u = C_{i}");
    }
}

#[test]
fn batch_sampling_agrees_with_single_draws() {
    // A guided table and a short one, batches not a multiple of GROUP.
    for n in [5000, 10] {
        let weights: Vec<f64> = (0..n).map(|i| ((i * 31) % 9) as f64).collect();
        let d = Discrete1D::new(&weights).unwrap();
        let us: Vec<f64> = (0..=1000).map(|k| k as f64 / 1000.0).collect();
        let mut out = vec![0u64; us.len()];
        d.sample_into(&us, &mut out);
        let mut reused = vec![(0, 0.0); us.len()];
        d.sample_reuse_into(&us, &mut reused);
        for ((&u, &i), &r) in us.iter().zip(&out).zip(&reused) {
            assert_eq!(i as usize, d.sample(u), "n = {n}, u = {u}");
            assert_eq!(r, d.sample_reuse(u), "n = {n}, u = {u}");
        }
    }
}

/// Tables whose guide-cell windows fail: a cluster of tiny weights in
/// one cell (answers past the window), lengths just over the guide's
/// minimum (windows past the table's end, read as its last sum), zeros
/// first and last (one table's first entry a window from its end).
fn window_tables() -> Vec<Vec<f64>> {
    let mut cluster: Vec<f64> = (0..400).map(|i| 1.0 + (i % 5) as f64).collect();
    cluster[150..250].fill(1e-9);
    let mut short = vec![vec![1.0; 64], vec![2.0; 71]];
    short[1][..3].fill(0.0);
    short[1][68..].fill(0.0);
    let ramp = (0..1000)
        .map(|i| ((i * i) % 97) as f64 * (i % 13) as f64)
        .collect();
    let late = [vec![0.0; 60], vec![1.0; 4]].concat();
    [vec![cluster, ramp, late], short].concat()
}

/// `u` on a grid, on every running sum and its neighbours, and
/// negative (drawn as 0, by the single search).
fn window_us(d: &Discrete1D) -> Vec<f64> {
    let mut us: Vec<f64> = (0..=3000).map(|k| k as f64 / 3000.0).collect();
    us.extend([-0.5, -0.0, -1e-300]);
    for &c in d.cdf.iter() {
        let u = c / d.sum();
        us.extend([u, u.next_down().max(0.0), u.next_up().min(1.0)]);
    }
    us
}

#[test]
fn side_by_side_searches_agree_where_windows_fail() {
    for weights in window_tables() {
        let d = Discrete1D::new(&weights).unwrap();
        let us = window_us(&d);
        let mut out = vec![0u64; us.len()];
        d.sample_into(&us, &mut out);
        let mut reused = vec![(0, 0.0); us.len()];
        d.sample_reuse_into(&us, &mut reused);
        let n = weights.len();
        for ((&u, &i), &r) in us.iter().zip(&out).zip(&reused) {
            assert_eq!(i as usize, d.sample(u), "n = {n}, u = {u}");
            assert_eq!(r, d.sample_reuse(u), "n = {n}, u = {u}");
            assert_eq!(i as usize, linear(&d, u), "n = {n}, u = {u}");
        }
    }
}

/// Draws of `search` (over `d`'s weights) side by side: those the
/// windows settle have the answer of a linear scan, and the rescaled `u`
/// of the single draw (from the running sums the search read); returns
/// how many were left to the single search.
fn lanes_redone(d: &Discrete1D, search: &Search<'_>, us: &[f64]) -> usize {
    let mut lanes = Lanes::new();
    let mut redone = 0;
    for us in us.chunks(GROUP) {
        for (k, &u) in us.iter().enumerate() {
            lanes.set(k, search, u);
        }
        let mut index = [0; GROUP];
        let redo = lanes.search(search, true, &mut index);
        let mut rescaled = [0.0f64; GROUP];
        lanes.rescale(&mut rescaled);
        for (k, &u) in us.iter().enumerate() {
            if redo & (1 << k) == 0 {
                assert_eq!(index[k] as usize, linear(d, u), "u = {u}");
                let single = search.rescale(u, index[k] as usize);
                assert_eq!(rescaled[k].to_bits(), single.to_bits(), "u = {u}");
            } else {
                redone += 1;
            }
        }
    }
    redone
}

#[test]
fn lanes_leave_to_the_single_search_the_draws_their_window_misses() {
    let mut redone = 0;
    for weights in window_tables() {
        let d = Discrete1D::new(&weights).unwrap();
        redone += lanes_redone_with_late_cells(&d, &window_us(&d));
    }
    // The cluster's draws and the late cells'.
    assert!(redone > 1000, "{redone}");
}

/// [`lanes_redone`] of `d`'s own guide and of one whose every cell
/// starts one entry late, as round-off could make one (see the test
/// below): the sum before it gives it away.
fn lanes_redone_with_late_cells(d: &Discrete1D, us: &[f64]) -> usize {
    let late: Vec<u32> = (d.guide.iter())
        .map(|&g| (g + 1).min(d.last as u32))
        .collect();
    let search = Search::new((d.weights(), &d.cdf, &late), (d.sum(), d.first, d.last));
    lanes_redone(d, &d.search(), us) + lanes_redone(d, &search, us)
}

#[test]
fn long_tables_with_a_sparser_guide_are_searched_side_by_side() {
    // Past 2^16 entries a guide cell spans 4 entries, not 2: a cluster
    // of tiny weights, a ramp, and `u` on a grid and on every 97th
    // running sum and its neighbours.
    let n = (1 << 16) + 1000;
    let weights: Vec<f64> = (0..n)
        .map(|i| match i {
            30_000..30_400 => 1e-9,
            _ => 1.0 + (i % 7) as f64,
        })
        .collect();
    let d = Discrete1D::new(&weights).unwrap();
    assert_eq!(d.guide.len(), n / 4 + 1);
    let mut us: Vec<f64> = (0..=3000).map(|k| k as f64 / 3000.0).collect();
    for &c in d.cdf.iter().step_by(97) {
        let u = c / d.sum();
        us.extend([u, u.next_down().max(0.0), u.next_up().min(1.0)]);
    }
    let redone = lanes_redone_with_late_cells(&d, &us);
    assert!(redone > 100, "{redone}");
    let mut out = vec![0u64; us.len()];
    d.sample_into(&us, &mut out);
    for (&u, &i) in us.iter().zip(&out) {
        assert_eq!(i as usize, d.sample(u), "u = {u}");
    }
}

/// Weights of long tables (one part group; groups of blocks whole or
/// with a part group of several blocks or of one short block): a
/// pattern, zeros across block and group boundaries (cells shared by
/// two blocks), a weight that spans many cells, leading and trailing
/// zeros.
fn long_tables() -> Vec<Vec<f64>> {
    let zeros = [
        SUM_BLOCK - 50..SUM_BLOCK + 50,
        SUM_GROUP - 9..2 * SUM_GROUP + 9,
    ];
    let sizes = [
        5000,
        2 * SUM_GROUP,
        SUM_GROUP + 3 * SUM_BLOCK + 5,
        3 * SUM_GROUP + 7,
    ];
    let mut tables = Vec::new();
    for n in sizes {
        let cases: [Box<dyn Fn(usize) -> f64>; 4] = [
            Box::new(|i| ((i * 7919) % 13) as f64),
            Box::new(|i| f64::from(!zeros.iter().any(|z| z.contains(&i)) || i == n / 2)),
            Box::new(|i| if i == n / 3 { 1e6 } else { 1.0 }),
            Box::new(|i| f64::from(i > 100 && i + 200 < n && i % 3 == 0)),
        ];
        tables.extend(cases.iter().map(|w| (0..n).map(w).collect()));
    }
    tables
}

#[test]
fn long_tables_are_summed_by_blocks() {
    for weights in long_tables() {
        let d = Discrete1D::new(&weights).unwrap();
        // Each block's sums in order from 0, offset by the sum in order
        // of the totals of the blocks before it: the same bits.
        let mut offset = 0.0;
        for (b, block) in weights.chunks(SUM_BLOCK).enumerate() {
            let mut acc = 0.0;
            for (i, &w) in block.iter().enumerate() {
                acc += w;
                assert_eq!(d.cdf[b * SUM_BLOCK + i], acc + offset);
            }
            offset += acc;
        }
        assert_eq!(d.sum(), offset);
        let exact: f64 = weights.iter().sum();
        assert!((d.sum() - exact).abs() <= 1e-12 * exact);
        for k in 0..=100 {
            let u = k as f64 / 100.0;
            let i = d.sample(u);
            assert_eq!(i, linear(&d, u), "u = {u}");
            assert!(weights[i] > 0.0);
        }
    }
}

#[test]
fn guide_cells_are_the_floors_of_the_scaled_sums() {
    let cases = [
        (65, 1.0),
        (250_001, 3.7e5),
        (1 << 20, 7.0),
        (4097, 1e-300),
        (65, 1e-310),
    ];
    for (len, sum) in cases {
        let cell = GuideCell::new(len, sum).unwrap();
        let cells = len - 1;
        // (Kept finite for a subnormal sum.)
        let scale = (cells as f64 / sum).min(f64::MAX);
        // Whole, half and nearly whole cells (ties and round-ups), and
        // sums past the total.
        let xs = (0..=4 * cells)
            .map(|k| k as f64 / 4.0)
            .chain([1e9, f64::MAX]);
        for x in xs.flat_map(|x| [x, x.next_down().max(0.0), x.next_up()]) {
            let c = x / scale;
            let floor = ((c * scale) as usize).min(cells);
            assert_eq!(cell.of(c) as usize, floor, "len {len}, x {x}");
        }
    }
}

#[test]
fn long_tables_get_the_guide_of_their_sums() {
    for (case, weights) in long_tables().iter().enumerate() {
        let d = Discrete1D::new(weights).unwrap();
        // Cell k holds the first entry whose sum's cell is k or more,
        // kept within the entries of positive weight; cells past the
        // last sum's, the last entry.
        let cell = GuideCell::new(d.guide.len(), d.sum()).unwrap();
        let mut expected = vec![d.last; d.guide.len()];
        let mut k = 0;
        for (i, &c) in d.cdf.iter().enumerate() {
            while k <= cell.of(c) as usize {
                expected[k] = i.clamp(d.first, d.last);
                k += 1;
            }
        }
        let guide: Vec<usize> = d.guide.iter().map(|&g| g as usize).collect();
        assert_eq!(guide, expected, "case {case}");
        // Filled in one pass over the table, the same guide.
        let mut one_pass = vec![0; d.guide.len()];
        fill_guide(&d.cdf, d.sum(), (d.first, d.last), &mut one_pass);
        assert_eq!(&one_pass[..], &d.guide[..], "case {case}");
    }
}

#[test]
fn negative_zero_draws_as_zero() {
    // u = -0.0 passes the [0, 1] check; the search compares the bits of
    // u·Σw, so -0.0 must count as +0.0 (also past leading zeros).
    let weights: Vec<f64> = (0..300).map(|i| if i < 5 { 0.0 } else { 1.0 }).collect();
    let d = Discrete1D::new(&weights).unwrap();
    assert_eq!(d.sample(-0.0f64), 5);
    assert_eq!(d.sample(-0.0f32), d.sample(0.0f32));
    assert_eq!(d.sample_reuse(-0.0f64), d.sample_reuse(0.0f64));
}

#[test]
fn weights_too_small_to_move_the_sums_leave_rescaled_numbers_in_the_unit_interval() {
    // The rescaled u divides by the step of the running sums, which is 0
    // at an entry too light to move them: the search must never return
    // one. Short (unguided) and long (guided) tables, single draws and
    // batches, u on a grid and at every running sum's own u.
    for n in [5, 300] {
        let weights: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 1 { 1e-30 } else { 1.0 + i as f64 })
            .collect();
        let d = Discrete1D::new(&weights).unwrap();
        let mut us: Vec<f64> = (0..=4000).map(|k| k as f64 / 4000.0).collect();
        us.extend((0..n).map(|i| d.cdf(i)));
        let mut batch = vec![(0, 0.0); us.len()];
        d.sample_reuse_into(&us, &mut batch);
        for (&u, &got) in us.iter().zip(&batch) {
            let (i, r) = d.sample_reuse(u);
            assert_eq!((i, r), got, "n = {n}, u = {u}");
            assert!(weights[i] >= 1.0, "n = {n}, u = {u}: entry {i}");
            assert!((0.0..1.0).contains(&r), "n = {n}, u = {u}: {r}");
            let r32 = d.sample_reuse(u as f32).1;
            assert!((0.0..1.0).contains(&r32), "n = {n}, u = {u}: {r32}");
        }
    }
}

#[test]
fn a_guide_cell_that_starts_too_late_is_caught() {
    // Round-off between u·G and the guide's thresholds could start a
    // cell one entry late (rare); shift every cell's start by one to
    // check that the search notices and still answers right.
    let n = 200;
    let weights: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64).collect();
    let d = Discrete1D::new(&weights).unwrap();
    let late: Vec<u32> = d
        .guide
        .iter()
        .map(|&g| (g + 1).min(d.last as u32))
        .collect();
    let search = Search::new((d.weights(), &d.cdf, &late), (d.sum(), d.first, d.last));
    for k in 0..=4000 {
        let u = k as f64 / 4000.0;
        assert_eq!(
            search.index(u, search.guide_cell(u)),
            linear(&d, u),
            "u = {u}"
        );
    }
}

proptest! {
    #[test]
    fn never_returns_a_zero_weight(
        weights in prop::collection::vec(prop_oneof![Just(0.0), 0.0..10.0f64], 1..3000),
        us in prop::collection::vec(0.0..=1.0f64, 50),
    ) {
        if let Ok(d) = Discrete1D::new(&weights) {
            for u in us.into_iter().chain([0.0, 1.0, f64::ONE_MINUS_EPSILON]) {
                let (i, r) = d.sample_reuse(u);
                prop_assert!(weights[i] > 0.0, "u = {} gave zero-weight index {}", u, i);
                prop_assert_eq!(i, linear(&d, u));
                prop_assert!((0.0..1.0).contains(&r));
            }
            // The CDF is monotone and ends at 1.
            prop_assert!((0..d.len()).all(|i| i == 0 || d.cdf(i) >= d.cdf(i - 1)));
            prop_assert_eq!(d.cdf(d.len() - 1), 1.0);
        }
    }

    #[test]
    fn constructor_never_panics(weights in prop::collection::vec(
        prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(-0.0), Just(f64::MAX), any::<f64>()],
        0..20,
    )) {
        let _ = Discrete1D::new(&weights);
    }
}
