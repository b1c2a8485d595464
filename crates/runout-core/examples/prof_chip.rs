use runout_core::chip::compare::{exact_values, exact_values_reference, sample_grid, Motion};
use runout_core::chip::*;
use runout_core::{Cutter, Runout};
fn kin(motion: Motion) -> ToolKinematics<Motion> {
    let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    let runout = Runout::new(0.010, 40f64.to_radians()).unwrap();
    ToolKinematics::new(
        &cutter,
        &runout,
        6000.0,
        0.0,
        SpindleSense::CounterClockwise,
        motion,
    )
    .unwrap()
}
fn swing() -> Motion {
    Motion::Swing(
        ConstantSwing::new(
            Vec3::new(40.0, 0.0, 0.0),
            Vec3::y(),
            60f64.to_radians(),
            0.0,
        )
        .unwrap(),
    )
}
fn cl_path() -> Motion {
    let pts: Vec<ClPoint> = (0..40)
        .map(|n| {
            let a = (0.5 * n as f64).to_radians();
            let b = if n % 2 == 0 { 0.0 } else { 0.3f64.to_radians() };
            ClPoint {
                p: Vec3::new(n as f64 - 10.0, 0.02 * (n as f64).powi(2), 0.0),
                u: Vec3::new(a.sin(), b.sin(), a.cos() * b.cos()).normalize(),
                feed: 40.0,
            }
        })
        .collect();
    Motion::Path(ClPath::new(&pts).unwrap())
}
fn main() {
    let which = std::env::args().nth(1).unwrap_or("swing".into());
    let reps: usize = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(3);
    let k = kin(if which == "swing" { swing() } else { cl_path() });
    let pts = sample_grid(4, &[0.0, 5.0, 10.0], 0.01, 0.25, 360);
    let opts = NewtonOptions::default();
    let mut it = 0u64;
    let mut hist = [0u64; 8];
    for q in pts.iter().filter(|_| std::env::args().nth(3).is_none()) {
        let geo = k.at_height(q.z);
        let ray = Ray::at(&k, &geo, q.tooth, q.t);
        for m in 1..=4 {
            let c = crossing_at(&k, &geo, &ray, q.tooth, m, q.t, &opts);
            it += c.iterations as u64;
            hist[(c.iterations as usize).min(7)] += 1;
        }
    }
    println!(
        "{which}: iterations per pass {:.3} hist {:?}",
        it as f64 / (4 * pts.len()) as f64,
        hist
    );
    let a = exact_values(&k, &pts);
    let b = exact_values_reference(&k, &pts);
    let diff = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x.to_bits() != y.to_bits())
        .count();
    println!("bit differences {diff} of {}", a.len());
    let old = std::env::args().nth(4).is_some();
    let mut s = 0.0;
    for _ in 0..reps {
        s += if old {
            exact_values_reference(&k, &pts)
        } else {
            exact_values(&k, &pts)
        }
        .iter()
        .sum::<f64>();
    }
    println!("{s}");
}
