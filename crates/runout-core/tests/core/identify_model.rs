//! The one-revolution evaluator of the full-signal fit agrees with `ForceModel::simulate`, its
//! analytic derivatives agree with finite differences, and the frequency-domain estimate (§4.7)
//! is exact on the linear chip model.

use runout_core::identify::*;
use runout_core::*;

fn coeffs() -> CuttingCoefficients {
    CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap()
}

fn compare(cutter: Cutter, runout: Runout, cut: Cut, disks: usize) {
    let model = ForceModel {
        cutter: cutter.clone(),
        runout,
        cut,
        coefficients: coeffs(),
    };
    let chip = ArcChip::new(&cutter, &runout, cut.fz()).unwrap();
    let s = model.simulate(&chip, &Sampling::new(1.0, 0.5, disks).unwrap());
    let rev = RevolutionModel::new(&cutter, &cut, 0.0, s.len(), disks);
    let e = runout.vector_at(0.0);
    let sums = rev.sums(e, runout.tilt(), false);
    let scale = s.fxy().into_iter().fold(0.0, f64::max);
    for (axis, v) in [
        (FrameAxis::X, &s.fx),
        (FrameAxis::Y, &s.fy),
        (FrameAxis::Z, &s.fz),
    ] {
        for (q, b) in sums.base.iter().enumerate() {
            let f = force_from_basis(axis, b, &coeffs());
            // same equations and discretisation: agreement to rounding (1e-9 of the peak force)
            assert!(
                (f - v[q]).abs() <= 1e-9 * scale,
                "{axis:?} sample {q}: {f} vs {}",
                v[q]
            );
        }
    }
}

#[test]
fn revolution_model_matches_simulation() {
    let c4 = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let r = Runout::new(0.012, 0.7).unwrap();
    let up = Cut::new(3000.0, 0.08, 2.0)
        .unwrap()
        .radial(2.0, MillingMode::Up, &c4)
        .unwrap();
    compare(c4.clone(), r, up, 20);
    let down = Cut::new(3000.0, 0.1, 1.5)
        .unwrap()
        .radial(3.0, MillingMode::Down, &c4)
        .unwrap();
    compare(c4.clone(), r.with_tilt(0.004, 2.0).unwrap(), down, 12);
    // variable pitch, 3 teeth, edge skipping runout (2ρ sin(π/3) > f_z)
    let c3 = Cutter::new(
        8.0,
        vec![
            110f64.to_radians(),
            120f64.to_radians(),
            130f64.to_radians(),
        ],
        0.0,
        f64::INFINITY,
        RadiusProfile::Flat,
    )
    .unwrap();
    let big = Runout::new(0.05, -1.2).unwrap();
    let slot = Cut::new(3000.0, 0.04, 1.0)
        .unwrap()
        .angles(0.3, 2.9)
        .unwrap();
    compare(c3, big, slot, 1);
    let c2 = Cutter::flat(6.0, 2, 0.0).unwrap();
    let cut2 = Cut::new(3000.0, 0.05, 1.0)
        .unwrap()
        .radial(1.0, MillingMode::Up, &c2)
        .unwrap();
    compare(c2, Runout::new(0.008, 2.5).unwrap(), cut2, 1);
}

#[test]
fn runout_derivatives_match_finite_differences() {
    let c = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let cut = Cut::new(3000.0, 0.08, 2.0)
        .unwrap()
        .radial(4.0, MillingMode::Down, &c)
        .unwrap();
    let m = RevolutionModel::new(&c, &cut, 0.013, 360, 10);
    let e = [0.006, -0.004];
    let tau = [0.001, 0.002];
    let s = m.sums(e, tau, true);
    let h = 1e-7;
    let kc = coeffs();
    for p in 0..4 {
        let mut ep = e;
        let mut em = e;
        let mut tp = tau;
        let mut tm = tau;
        match p {
            0 | 1 => {
                ep[p] += h;
                em[p] -= h;
            }
            _ => {
                tp[p - 2] += h;
                tm[p - 2] -= h;
            }
        }
        let (sp, sm) = (m.sums(ep, tp, false), m.sums(em, tm, false));
        let mut worst: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for q in 0..360 {
            for axis in [FrameAxis::X, FrameAxis::Y, FrameAxis::Z] {
                let fd = (force_from_basis(axis, &sp.base[q], &kc)
                    - force_from_basis(axis, &sm.base[q], &kc))
                    / (2.0 * h);
                let an = runout_gradient(axis, &s.deriv[q][p], &kc);
                worst = worst.max((fd - an).abs());
                scale = scale.max(an.abs());
            }
        }
        // central differences of a piecewise-linear function: exact except at the few samples
        // where a tooth's h crosses 0 or the active m switches within ±h → 1e-4 relative
        assert!(worst <= 1e-4 * scale, "param {p}: {worst} vs scale {scale}");
    }
}

/// Linear chip model (methods.md §4.7): h = f_z sin φ + first-order (R_i − R_{i−1}), unclipped.
struct LinearChip {
    cutter: Cutter,
    runout: Runout,
    fz: f64,
}
struct LinearAt {
    dr: Vec<f64>,
    fz: f64,
}
impl ChipThickness for LinearChip {
    type AtHeight = LinearAt;
    fn name(&self) -> &'static str {
        "linear"
    }
    fn at_height(&self, z: f64) -> LinearAt {
        let k = self.cutter.teeth();
        let r: Vec<f64> = (0..k)
            .map(|i| self.runout.tooth_radius_first_order(&self.cutter, i, z))
            .collect();
        LinearAt {
            dr: (0..k).map(|i| r[i] - r[(i + k - 1) % k]).collect(),
            fz: self.fz,
        }
    }
}
impl ChipAtHeight for LinearAt {
    fn thickness(&self, tooth: usize, _phi: f64, s: f64, _c: f64) -> f64 {
        self.fz * s + self.dr[tooth]
    }
}

#[test]
fn frequency_estimate_exact_on_linear_chip_model() {
    // methods.md §7: linear chip model, ρ 8 µm, α₀ −50° → exactly 8.00 µm, −50.00°
    // (and 12 µm / 100°). Engagement 30°..150° keeps h > 0 so the simulation is the linear model.
    for (k, helix, rho, lam) in [
        (4, 0.0, 0.008, -50.0),
        (4, 30.0, 0.012, 100.0),
        (2, 30.0, 0.008, 40.0),
        (3, 30.0, 0.005, -150.0),
    ] {
        let c = Cutter::flat(10.0, k, f64::to_radians(helix)).unwrap();
        let r = Runout::new(rho, f64::to_radians(lam)).unwrap();
        let cut = Cut::new(3240.0, 0.1, 1.0)
            .unwrap()
            .angles(30f64.to_radians(), 150f64.to_radians())
            .unwrap();
        let kc = coeffs().without_edge();
        let model = ForceModel {
            cutter: c.clone(),
            runout: r,
            cut,
            coefficients: kc,
        };
        let chip = LinearChip {
            cutter: c.clone(),
            runout: r,
            fz: 0.1,
        };
        let disks = if helix > 0.0 { 16 } else { 1 };
        let s = model.simulate(&chip, &Sampling::new(1.0, 0.5, disks).unwrap());
        let w = AveragedWaveform::average(
            0.0,
            s.len(),
            &[(FrameAxis::X, &s.fx), (FrameAxis::Y, &s.fy)],
        )
        .unwrap();
        let est = frequency_estimate(
            &[WaveformCase {
                cutter: c,
                cut,
                waveform: w,
            }],
            &kc,
            disks,
        )
        .unwrap();
        // exact up to rounding (1e-6 µm, 1e-6°)
        assert!((est.offset - rho).abs() < 1e-9, "{k} {est:?}");
        assert!((est.angle.to_degrees() - lam).abs() < 1e-6, "{k} {est:?}");
    }
    // K = 2 with straight flutes: the offset across the tooth line changes neither radius to
    // first order — unobservable; the estimate must refuse rather than guess.
    let c = Cutter::flat(10.0, 2, 0.0).unwrap();
    let cut = Cut::new(3240.0, 0.1, 1.0)
        .unwrap()
        .angles(30f64.to_radians(), 150f64.to_radians())
        .unwrap();
    let n = 720;
    let model = RevolutionModel::new(&c, &cut, 0.0, n, 1);
    let s = model.sums([0.004, 0.003], [0.0, 0.0], false);
    let fx: Vec<f64> = s
        .base
        .iter()
        .map(|b| force_from_basis(FrameAxis::X, b, &coeffs()))
        .collect();
    let w = AveragedWaveform::average(0.0, n, &[(FrameAxis::X, &fx)]).unwrap();
    let e = frequency_estimate(
        &[WaveformCase {
            cutter: c,
            cut,
            waveform: w,
        }],
        &coeffs(),
        1,
    );
    assert!(matches!(e, Err(IdentifyError::Singular { .. })), "{e:?}");
}
