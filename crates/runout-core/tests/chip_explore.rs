use runout_core::chip::compare::*;
use runout_core::chip::*;
use runout_core::{Cutter, Runout};

fn case(r: f64, k: usize, fz: f64, rho: f64, motion: Motion, heights: &[f64], revs: f64) {
    let cutter = Cutter::flat(2.0 * r, k, 30.0).unwrap();
    let runout = Runout::new(rho, 40f64.to_radians()).unwrap();
    let kin = ToolKinematics::new(&cutter, &runout, 6000.0, 0.0, SpindleSense::CounterClockwise, motion).unwrap();
    let _ = fz;
    let pts = sample_grid(k, heights, 0.01, 0.01 * revs, 360);
    for refine in [false, true] {
        let v = evaluate_models(&kin, &pts, &EquivalentParams { k1: 1.0, k2: 1.0, phase_refinement: refine });
        let a = error_metrics(&v.arc, &v.exact);
        let c = error_metrics(&v.circle, &v.exact);
        let e = error_metrics(&v.equivalent, &v.exact);
        println!("R{r} K{k} fz{fz} rho{rho} refine={refine}: arc {:.3}% ({:.3}%) circle {:.3}% eq {:.3}% ({:.3}%) n={}", a.mean_relative*100., a.normalised_mae*100., c.mean_relative*100., e.mean_relative*100., e.normalised_mae*100., e.points_relative);
    }
}

fn straight(k: usize, fz: f64) -> Motion {
    Motion::Straight(StraightFeed { p0: Vec3::zeros(), v: Vec3::new(fz * k as f64 * 100.0, 0.0, 0.0), u: Vec3::z(), e1: Vec3::x() })
}

#[test]
fn explore() {
    case(5.0, 4, 0.05, 0.01, straight(4, 0.05), &[5.0], 1.0);
    case(5.0, 4, 0.10, 0.01, straight(4, 0.10), &[5.0], 1.0);
    case(5.0, 4, 0.20, 0.01, straight(4, 0.20), &[5.0], 1.0);
    case(2.0, 4, 0.10, 0.005, straight(4, 0.10), &[2.0], 1.0);
    case(3.0, 4, 0.20, 0.01, straight(4, 0.20), &[3.0], 1.0);
    case(4.0, 3, 0.15, 0.02, straight(3, 0.15), &[4.0], 1.0);
    let sw = ConstantSwing::new(Vec3::new(40.0, 0.0, 0.0), Vec3::y(), 60f64.to_radians(), 0.0).unwrap();
    let sw = ConstantSwing { e1: Vec3::x(), ..sw };
    case(5.0, 4, 0.1, 0.01, Motion::Swing(sw), &[0.0, 10.0, 20.0], 1.0);
    let sw2 = ConstantSwing::new(Vec3::new(40.0, 0.0, 0.0), Vec3::new(1.0, 0.3, 0.0), 60f64.to_radians(), 0.0).unwrap();
    let sw2 = ConstantSwing { e1: Vec3::x(), ..sw2 };
    case(5.0, 4, 0.1, 0.01, Motion::Swing(sw2), &[0.0, 10.0, 20.0], 1.0);
    case(0.25, 2, 0.002, 0.002, straight(2, 0.002), &[0.1], 1.0);
}
