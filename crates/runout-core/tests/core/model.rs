//! Model tests: actual radii (methods.md §7), first-order form, seed conventions, validation.

use approx::assert_abs_diff_eq;
use proptest::prelude::*;
use runout_core::runout::seed::{
    lambda_from_seed003_phase, seed003_phase_from_lambda, tooth_from_seed000_edge,
};
use runout_core::*;

/// methods.md §7 vectors are given in seed 000's edge order k = 1..K with θ = λ.
fn radii_seed_order(teeth: usize, theta_deg: f64) -> Vec<f64> {
    let c = Cutter::flat(0.5, teeth, 0.0).unwrap();
    let r = Runout::new(0.005, theta_deg.to_radians()).unwrap();
    (1..=teeth)
        .map(|k| r.tooth_radius(&c, tooth_from_seed000_edge(k, teeth).unwrap(), 0.0))
        .collect()
}

#[test]
fn actual_radius_vectors_of_methods_section_7() {
    // printed to 9 decimals (1e-9 mm); we allow 1e-9
    let cases: [(usize, f64, &[f64]); 3] = [
        (2, 60.0, &[0.252537126, 0.247537876]),
        (3, 40.0, &[0.253850568, 0.250916561, 0.245307498]),
        (
            4,
            -120.0,
            &[0.247537876, 0.245682593, 0.252537126, 0.254342414],
        ),
    ];
    for (k, th, want) in cases {
        let got = radii_seed_order(k, th);
        for (g, w) in got.iter().zip(want) {
            assert_abs_diff_eq!(*g, *w, epsilon = 1e-9);
        }
    }
    let r = radii_seed_order(2, 60.0);
    assert_abs_diff_eq!(r[0] - r[1], 0.004999250, epsilon = 1e-9);
}

#[test]
fn first_order_radius_is_within_second_order_term() {
    // |R_i − R_i^(1)| ≤ ρ²/(2R) (+ rounding): the neglected term of eq. (0.3).
    let c = Cutter::flat(10.0, 4, 0.0).unwrap();
    let r = Runout::new(0.02, 0.7).unwrap();
    for i in 0..4 {
        let d = (r.tooth_radius(&c, i, 0.0) - r.tooth_radius_first_order(&c, i, 0.0)).abs();
        assert!(d <= 0.02f64.powi(2) / (2.0 * 5.0) + 1e-15, "tooth {i}: {d}");
    }
}

#[test]
fn seed003_phase_round_trip_and_table2_test1() {
    // Table 2 test 1: φ = 100.0°, α₀ = −35.0° → λ = α₀ (K = 4, λ = φ − 135°)
    assert_abs_diff_eq!(
        lambda_from_seed003_phase(100f64.to_radians(), 4).to_degrees(),
        -35.0,
        epsilon = 1e-9
    );
    for k in 2..8 {
        let l = 0.3;
        assert_abs_diff_eq!(
            lambda_from_seed003_phase(seed003_phase_from_lambda(l, k), k),
            l,
            epsilon = 1e-12
        );
    }
}

#[test]
fn variable_pitch_tooth_angles_and_gaps() {
    let p: Vec<f64> = [80.0f64, 100.0, 80.0, 100.0]
        .iter()
        .map(|d| d.to_radians())
        .collect();
    let c = Cutter::new(10.0, p, 0.0, 30.0, RadiusProfile::Flat).unwrap();
    assert_abs_diff_eq!(c.tooth_angle(1, 0.0).to_degrees(), -80.0, epsilon = 1e-12);
    assert_abs_diff_eq!(c.tooth_angle(2, 0.0).to_degrees(), -180.0, epsilon = 1e-12);
    // gap from tooth i−1 to i is pitch[i−1]; from i−K to i is a full turn
    assert_abs_diff_eq!(c.gap(1, 1).to_degrees(), 80.0, epsilon = 1e-12);
    assert_abs_diff_eq!(c.gap(0, 1).to_degrees(), 100.0, epsilon = 1e-12);
    assert_abs_diff_eq!(c.gap(2, 4).to_degrees(), 360.0, epsilon = 1e-12);
}

#[test]
fn invalid_parameters_name_the_parameter() {
    let e = Cutter::flat(0.0, 4, 0.0).unwrap_err();
    assert_eq!(e.param, "diameter_mm");
    assert_eq!(Cutter::flat(10.0, 0, 0.0).unwrap_err().param, "teeth");
    assert_eq!(
        Cutter::flat(f64::NAN, 2, 0.0).unwrap_err().param,
        "diameter_mm"
    );
    assert_eq!(
        Cutter::flat(10.0, 2, 95.0f64.to_radians())
            .unwrap_err()
            .param,
        "helix_deg"
    );
    let bad_pitch = Cutter::new(10.0, vec![1.0, 1.0], 0.0, 10.0, RadiusProfile::Flat).unwrap_err();
    assert_eq!(bad_pitch.param, "pitch_deg");
    assert_eq!(Cut::new(1000.0, 0.0, 1.0).unwrap_err().param, "fz_mm");
    assert_eq!(Cut::new(1000.0, 0.1, -1.0).unwrap_err().param, "ap_mm");
    let c = Cutter::flat(10.0, 2, 0.0).unwrap();
    assert_eq!(
        Cut::new(1000.0, 0.1, 1.0)
            .unwrap()
            .radial(11.0, MillingMode::Up, &c)
            .unwrap_err()
            .param,
        "ae_mm"
    );
    assert_eq!(Runout::new(-0.001, 0.0).unwrap_err().param, "runout_um");
}

#[test]
fn immersion_angles_follow_conventions() {
    let c = Cutter::flat(10.0, 4, 0.0).unwrap();
    let base = Cut::new(1000.0, 0.1, 1.0).unwrap();
    let (s, e) = base.radial(2.0, MillingMode::Up, &c).unwrap().immersion(&c);
    assert_abs_diff_eq!(s, 0.0);
    assert_abs_diff_eq!(e, 0.6f64.acos(), epsilon = 1e-15);
    let (s, e) = base
        .radial(2.0, MillingMode::Slot, &c)
        .unwrap()
        .immersion(&c);
    assert_abs_diff_eq!(e - s, std::f64::consts::PI);
}

proptest! {
    /// Exact radius equals the law of cosines of eq. (0.1) for any tooth, height and helix.
    #[test]
    fn exact_radius_law_of_cosines(k in 1usize..8, rho_um in 0.0f64..50.0, lam in -3.2f64..3.2, z in 0.0f64..20.0, helix in 0.0f64..45.0) {
        let c = Cutter::flat(8.0, k, f64::to_radians(helix)).unwrap();
        let r = Runout::new(rho_um * 1e-3, lam).unwrap();
        for i in 0..k {
            let psi = c.tooth_angle(i, z);
            let rho = rho_um * 1e-3;
            let want = (16.0 + rho * rho + 2.0 * 4.0 * rho * (psi - lam).cos()).sqrt();
            prop_assert!((r.tooth_radius(&c, i, z) - want).abs() < 1e-12);
        }
    }
}
