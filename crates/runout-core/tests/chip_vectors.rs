use runout_core::chip::*;
use runout_core::{Cutter, Runout};

fn ref_kin() -> ToolKinematics<StraightFeed> {
    let cutter = Cutter::flat(10.0, 4, 30.0).unwrap();
    let runout = Runout::new(0.010, 40f64.to_radians()).unwrap();
    let motion = StraightFeed { p0: Vec3::zeros(), v: Vec3::new(40.0, 0.0, 0.0), u: Vec3::z(), e1: Vec3::x() };
    ToolKinematics::new(&cutter, &runout, 6000.0, 0.0, SpindleSense::CounterClockwise, motion).unwrap()
}

#[test]
fn methods_section7_vectors() {
    let kin = ref_kin();
    for (frac, ex, arc, eq) in [(5.0, 92.987, 93.039, 93.146), (10.0, 68.603, 67.631, 68.711)] {
        let t = 0.01 * (1.0 + frac / 48.0);
        let e = exact_iuct(&kin, 0, 5.0, t, &NewtonOptions::default());
        let c = closed_forms(&kin, 0, 5.0, t, &EquivalentParams::analytic_unrefined());
        let r = closed_forms(&kin, 0, 5.0, t, &EquivalentParams::default());
        println!("{} {} {} {} refined {} circle {} iters {}", frac, e.h()*1e3, c.arc*1e3, c.equivalent*1e3, r.equivalent*1e3, c.circle*1e3, e.iterations);
        assert!((e.h() * 1e3 - ex).abs() < 5e-4);
        assert!((c.arc * 1e3 - arc).abs() < 5e-4);
        assert!((c.equivalent * 1e3 - eq).abs() < 5e-4);
    }
}
