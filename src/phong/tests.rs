use super::*;
use std::f64::consts::PI;

fn phong(n: f64) -> Phong {
    Phong::new([0.3, 0.2, 0.1], [0.5, 0.6, 0.7], n, Selection::Max).unwrap()
}

#[test]
fn selection_uses_the_original_maxima() {
    let p = phong(10.0);
    assert!((p.diffuse_probability() - 0.3 / (0.3 + 0.7)).abs() < 1e-15);
    let q = Phong::new([0.3, 0.2, 0.1], [0.5, 0.6, 0.7], 10.0, Selection::Luminance).unwrap();
    let (d, s) = (luminance([0.3, 0.2, 0.1]), luminance([0.5, 0.6, 0.7]));
    assert!((q.diffuse_probability() - d / (d + s)).abs() < 1e-15);
    let black = Phong::new([0.0; 3], [0.0; 3], 1.0, Selection::Max).unwrap();
    let s = black.sample([0.0, 0.0, 1.0], [0.3, 0.4, 0.5]);
    assert_eq!(s.weight, [0.0; 3]);
}

#[test]
fn errors() {
    assert!(matches!(
        Phong::new([0.6; 3], [0.5; 3], 1.0, Selection::Max),
        Err(Error::NotEnergyConserving { .. })
    ));
    assert!(Phong::new([-0.1, 0.0, 0.0], [0.5; 3], 1.0, Selection::Max).is_err());
    assert!(Phong::new([0.1; 3], [0.5; 3], -1.0, Selection::Max).is_err());
    assert!(Phong::new([0.1; 3], [0.5; 3], f64::NAN, Selection::Max).is_err());
}

/// The one-at-a-time forms give what the batch forms give, with a
/// glossy part and without one; without one, so do the diffuse forms.
#[test]
fn one_at_a_time_matches_the_batch_forms() {
    fn check<F: Real + std::fmt::Debug>(p: &Phong) {
        let wi = [0.3, -0.2, 0.932_737_905_308_881_5].map(F::c);
        let view = p.view(wi);
        assert_eq!(
            format!("{view:?}"),
            format!("{:?}", PhongView::from_terms(wi, p.view_terms()))
        );
        for k in 0..500 {
            let u = [0.618_034, 0.414_214, 0.732_051].map(|a| F::c((k as f64 * a) % 1.0));
            let (a, b) = (view.sample(u), view.sample_one(u[2], [u[0], u[1]]));
            assert_eq!(a, b, "{p:?} {u:?}");
            // Toward the sample and off it (the mirror direction's
            // neighbourhood, where the lobe is largest).
            if !p.is_glossy() {
                assert_eq!(a, view.sample_diffuse([u[0], u[1]]), "{p:?} {u:?}");
            }
            for wo in [a.wo, [F::c(0.01), F::c(-0.02), F::c(0.9997)], reflect(wi)] {
                let (f, pdf) = view.eval_pdf_one(wo);
                assert_eq!((f, pdf), (view.eval(wo), view.pdf(wo)), "{p:?} {wo:?}");
                assert_eq!((f, pdf), view.eval_pdf(wo), "{p:?} {wo:?}");
                if !p.is_glossy() {
                    assert_eq!((f, pdf), view.eval_pdf_diffuse(wo), "{p:?} {wo:?}");
                }
            }
        }
    }
    let rho = [0.5, 0.4, 0.3];
    let with = |specular, n| Phong::new(rho, specular, n, Selection::Max).unwrap();
    for p in [
        phong(20.0),
        with([0.0; 3], 1.0),
        // A glossy part so small that p_d rounds to 1 in f32.
        with([1e-9; 3], 1e6),
        Phong::new([0.0; 3], [0.0; 3], 1.0, Selection::Max).unwrap(),
        with([0.2; 3], 0.0),
        with([0.2; 3], MAX_EXPONENT),
    ] {
        check::<f32>(&p);
        check::<f64>(&p);
    }
}

#[test]
fn sample_rows_writes_the_samples_of_sample() {
    let view = phong(20.0).view([0.3f32, -0.2, 0.932_737_9]);
    // Two blocks and a part, the rows made by `prepare`.
    let n = 2 * SAMPLE_BLOCK + 37;
    let rows: Vec<u32> = (0..n as u32).collect();
    let u = |k: &u32| [0.618_034, 0.414_214, 0.732_051].map(|a: f32| (*k as f32 * a) % 1.0);
    let (mut wo, mut pdf, mut weight) = (vec![[0.0; 3]; n], vec![0.0; n], vec![[0.0; 3]; n]);
    let mut component = vec![9i64; n];
    let out = PhongSamples {
        wo: &mut wo,
        pdf: &mut pdf,
        weight: &mut weight,
        component: &mut component,
    };
    view.sample_rows(&rows, u, out);
    for (k, row) in rows.iter().enumerate() {
        let s = view.sample(u(row));
        assert_eq!(
            (wo[k], pdf[k], weight[k]),
            (s.wo, s.pdf, s.weight),
            "row {k}"
        );
        assert_eq!(component[k], i64::from(s.component));
    }
    assert!(component.contains(&0) && component.contains(&1));
}

#[test]
fn below_the_surface_is_black_and_weights_are_finite() {
    let p = phong(5.0);
    let wi = [0.0, (80f64.to_radians()).sin(), (80f64.to_radians()).cos()];
    assert_eq!(p.eval(wi, [0.0, 0.0, -1.0]), [0.0; 3]);
    assert_eq!(p.eval([0.0, 0.0, -1.0], [0.0, 0.0, 1.0]), [0.0; 3]);
    for k in 0..1000 {
        let u = [
            k as f64 / 999.0,
            (k * 7 % 1000) as f64 / 999.0,
            (k * 13 % 1000) as f64 / 999.0,
        ];
        let s = p.sample(wi, u);
        assert!(s.weight.iter().all(|w| w.is_finite() && *w >= 0.0));
        assert!((dot(s.wo, s.wo) - 1.0).abs() < 1e-12);
        if s.wo[2] <= 0.0 {
            assert_eq!(s.weight, [0.0; 3]);
        }
    }
}

#[test]
fn pdf_integrates_to_one_over_the_sphere() {
    for n in [0.0, 1.0, 30.0] {
        let p = phong(n);
        let wi = [0.5f64, 0.0, 0.75f64.sqrt()];
        let total = crate::quadrature::integrate_sphere(|wo| p.pdf(wi, wo), 400, 4000);
        assert!((total - 1.0).abs() < 2e-3, "n = {n}: {total}");
    }
}

/// The parameters read back; `f_r` and the density at chosen directions
/// are `ρd/π + ρs (n + 2)/(2π) cos^n α` and `p_d cos θo/π + (1 − p_d)
/// (n + 1)/(2π) cos^n α`, with α from the mirror direction `(−x, −y, z)`
/// of `wi`.
#[test]
fn eval_and_pdf_known_values() {
    let p = phong(10.0);
    assert_eq!(
        (p.diffuse(), p.specular(), p.exponent()),
        ([0.3, 0.2, 0.1], [0.5, 0.6, 0.7], 10.0)
    );
    let wi = [0.6, -0.1, (1.0f64 - 0.37).sqrt()];
    let wo = [-0.5, 0.2, (1.0f64 - 0.29).sqrt()];
    let cos_alpha = -wi[0] * wo[0] - wi[1] * wo[1] + wi[2] * wo[2];
    let lobe = cos_alpha.powf(10.0);
    let f = p.eval(wi, wo);
    for k in 0..3 {
        let expected = p.diffuse()[k] / PI + p.specular()[k] * 12.0 / (2.0 * PI) * lobe;
        assert!((f[k] - expected).abs() < 1e-12 * expected, "{k}: {f:?}");
    }
    let pd = p.diffuse_probability();
    let pdf = pd * wo[2] / PI + (1.0 - pd) * 11.0 / (2.0 * PI) * lobe;
    assert!((p.pdf(wi, wo) - pdf).abs() < 1e-12 * pdf);
}

/// At normal incidence the lobe is centred on the normal, and the
/// energy-normalised BRDF reflects `ρd + ρs` of the light: `2π ∫ f_r(μ)
/// μ dμ` over `μ = cos θ` (midpoint rule).
#[test]
fn albedo_at_normal_incidence_is_the_sum_of_the_reflectances() {
    for n in [0.0, 3.0, 40.0] {
        let p = phong(n);
        let steps = 20_000;
        let mut albedo = [0.0; 3];
        for j in 0..steps {
            let mu = (j as f64 + 0.5) / steps as f64;
            let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
            let f = p.eval([0.0, 0.0, 1.0], wo);
            for k in 0..3 {
                albedo[k] += 2.0 * PI * f[k] * mu / steps as f64;
            }
        }
        for k in 0..3 {
            let expected = p.diffuse()[k] + p.specular()[k];
            assert!((albedo[k] - expected).abs() < 1e-6, "n = {n}: {albedo:?}");
        }
    }
}

/// Nothing is reflected from or toward the horizon itself, and the lobe
/// is 0 where `cos α = 0` exactly, also for `n = 0` (where `0⁰` would
/// be 1).
#[test]
fn the_horizon_and_the_lobes_edge_are_black() {
    let p = phong(4.0);
    let up = [0.0, 0.6, 0.8];
    assert_eq!(p.eval([1.0, 0.0, 0.0], up), [0.0; 3]);
    assert_eq!(p.eval(up, [0.0, -1.0, 0.0]), [0.0; 3]);
    let flat = phong(0.0);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let (wi, wo) = ([h, 0.0, h], [h, 0.0, h]); // mirror (−h, 0, h) ⟂ wo
    let pd = flat.diffuse_probability();
    assert!((flat.pdf(wi, wo) - pd * h / PI).abs() < 1e-15);
    let f = flat.eval(wi, wo);
    for (v, rho) in f.iter().zip(flat.diffuse()) {
        assert!((v - rho / PI).abs() < 1e-15);
    }
}

/// A sample's weight is `f_r cos θo / pdf` (0 below the surface), and
/// its part is the diffuse one exactly when `u[2] < p_d` (at `u[2] =
/// p_d`, the glossy one), in both forms.
#[test]
fn sample_weight_and_component() {
    let p = phong(15.0);
    let wi = [0.3, 0.2, (1.0f64 - 0.13).sqrt()];
    let view = p.view(wi);
    let pd = p.diffuse_probability();
    for k in 0..200 {
        let u2 = match k {
            0 => pd,
            1 => pd - 1e-12,
            _ => (k as f64 * 0.618_034) % 1.0,
        };
        let u = [
            (k as f64 * 0.414_214) % 1.0,
            (k as f64 * 0.732_051) % 1.0,
            u2,
        ];
        for s in [view.sample(u), view.sample_one(u[2], [u[0], u[1]])] {
            assert_eq!(s.component, u8::from(u2 >= pd), "u = {u:?}");
            let f = p.eval(wi, s.wo);
            let cos = s.wo[2].max(0.0);
            for (w, v) in s.weight.iter().zip(f) {
                let expected = v * cos / s.pdf;
                assert!((w - expected).abs() <= 1e-12 * expected.max(1e-300));
            }
        }
    }
}
