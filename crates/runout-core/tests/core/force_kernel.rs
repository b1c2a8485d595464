//! Issue 13 item 6 / issue 18 item 1: the one shared force kernel against the two loops it
//! replaced (kept as `force::baseline::simulate` and `RevolutionModel::sums_baseline`).
//!
//! The kernel takes every decision (engagement window, h > 0, the active term of the min) and
//! forms every term with the same floating-point operations, in the same order per sample, as
//! the old loops: the simulation is compared **bit for bit**, and so are the identification's
//! sums in a one-thread pool. With several threads the identification sums its disks in
//! rayon's (run-dependent) grouping, old and new alike: there the tolerance is 1e-12 relative to
//! the largest magnitude of each row (the grouping moves a sum by a few ulp of its largest term,
//! ≈ 1e-15; a model change, e.g. one edge force switched, is ≥ 1e-4).

use runout_core::force::baseline;
use runout_core::identify::RevolutionModel;
use runout_core::*;

fn exact(name: &str, a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{name}: length");
    for (q, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            x.to_bits() == y.to_bits(),
            "{name}[{q}]: kernel {x} vs baseline {y}"
        );
    }
}

fn close(name: &str, a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{name}: length");
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    for (q, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= 1e-12 * scale,
            "{name}[{q}]: kernel {x} vs baseline {y} (scale {scale})"
        );
    }
}

fn same(a: &ForceSeries, b: &ForceSeries) {
    exact("fx", &a.fx, &b.fx);
    exact("fy", &a.fy, &b.fy);
    exact("fz", &a.fz, &b.fz);
    exact("torque", &a.torque, &b.torque);
    exact("max_chip", &a.max_chip, &b.max_chip);
    exact("own_peak", &a.own_peak_fxy, &b.own_peak_fxy);
    for (x, y) in a.chip.iter().zip(&b.chip) {
        exact("chip", x, y);
    }
    assert_eq!(a.angle, b.angle);
}

fn cutters() -> Vec<Cutter> {
    let tau = std::f64::consts::TAU;
    vec![
        Cutter::flat(10.0, 4, 30f64.to_radians()).unwrap(),
        Cutter::flat(10.0, 4, 0.0).unwrap(),
        Cutter::new(
            8.0,
            vec![1.4, 1.7, 1.5, tau - 4.6],
            35f64.to_radians(),
            f64::INFINITY,
            RadiusProfile::Flat,
        )
        .unwrap(),
        Cutter::new(
            6.0,
            vec![tau / 3.0; 3],
            30f64.to_radians(),
            20.0,
            RadiusProfile::Ball,
        )
        .unwrap(),
    ]
}

fn model(cutter: &Cutter, mode: MillingMode, ae: f64, ap: f64) -> ForceModel {
    let cut = Cut::new(3240.0, 0.08, ap)
        .unwrap()
        .radial(ae, mode, cutter)
        .unwrap();
    ForceModel {
        cutter: cutter.clone(),
        runout: Runout::new(0.012, 0.7).unwrap(),
        cut,
        coefficients: CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1])
            .unwrap(),
    }
}

#[test]
fn simulate_equals_the_baseline_loop() {
    for c in cutters() {
        for (mode, ae, ap) in [
            (MillingMode::Down, 2.0, 1.0),
            (MillingMode::Up, 1.0, 2.5),
            (MillingMode::Down, 2.0 * c.radius(), 1.5),
        ] {
            let m = model(&c, mode, ae.min(2.0 * c.radius()), ap);
            for (revs, step, disks) in [(1.0, 0.01, 1), (3.3, 0.25, 37), (2.0, 1.0, 8)] {
                let s = Sampling::new(revs, step, disks).unwrap();
                let arc = ArcChip::new(&c, &m.runout, 0.08).unwrap();
                same(&m.simulate(&arc, &s), &baseline::simulate(&m, &arc, &s));
                same(
                    &m.simulate_general(&arc, &s),
                    &baseline::simulate_general(&m, &arc, &s),
                );
                let eq = EquivalentChip::new(&c, &m.runout, 0.08, Default::default()).unwrap();
                same(&m.simulate(&eq, &s), &baseline::simulate(&m, &eq, &s));
            }
        }
    }
}

#[test]
fn no_runout_and_exact_chip_equal_the_baseline_loop() {
    // zero runout puts h = 0 exactly at the window's ends: the h > 0 switch must match
    let c = Cutter::flat(10.0, 4, 0.0).unwrap();
    let mut m = model(&c, MillingMode::Down, 2.0, 1.0);
    m.runout = Runout::none();
    let s = Sampling::new(1.0, 0.01, 1).unwrap();
    let arc = ArcChip::new(&c, &m.runout, 0.08).unwrap();
    same(&m.simulate(&arc, &s), &baseline::simulate(&m, &arc, &s));
    let ex = ExactChip::new(&c, &m.runout, 0.08).unwrap();
    let s = Sampling::new(1.0, 0.5, 5).unwrap();
    same(&m.simulate(&ex, &s), &baseline::simulate(&m, &ex, &s));
}

#[test]
fn revolution_sums_equal_the_baseline_loop() {
    revolution_sums(close);
}

#[test]
fn revolution_sums_equal_the_baseline_loop_bit_for_bit_on_one_thread() {
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    one.install(|| revolution_sums(exact));
}

fn revolution_sums(check: fn(&str, &[f64], &[f64])) {
    for c in cutters() {
        for (mode, ae, ap) in [(MillingMode::Down, 2.0, 1.0), (MillingMode::Up, 1.0, 2.5)] {
            let m = model(&c, mode, ae, ap);
            for (n, disks, start) in [(360, 1, 0.0), (384, 40, 0.3), (1440, 9, -2.0)] {
                for edge in [false, true] {
                    let mut rev = RevolutionModel::new(&c, &m.cut, start, n, disks);
                    rev.edge_in_window = edge;
                    let (e, tau) = ([0.007, -0.004], [0.001, 0.002]);
                    for (np, tilt) in [(2, false), (4, true)] {
                        for general in [false, true] {
                            let a = if general {
                                rev.sums_general(e, tau, tilt)
                            } else {
                                rev.sums(e, tau, tilt)
                            };
                            let b = rev.sums_baseline(e, tau, np, general);
                            for r in 0..16 {
                                let x: Vec<f64> = a.base.iter().map(|v| v[r]).collect();
                                let y: Vec<f64> = b.base.iter().map(|v| v[r]).collect();
                                check(&format!("row {r}"), &x, &y);
                            }
                            for p in 0..np {
                                for r in 0..8 {
                                    let x: Vec<f64> = a.deriv.iter().map(|v| v[p][r]).collect();
                                    let y: Vec<f64> = b.deriv.iter().map(|v| v[p][r]).collect();
                                    check(&format!("d{p} row {r}"), &x, &y);
                                }
                            }
                        }
                    }
                    let a = rev.base_sums(e, tau);
                    assert!(a.deriv.iter().all(|d| d.is_empty()));
                }
            }
        }
    }
}
