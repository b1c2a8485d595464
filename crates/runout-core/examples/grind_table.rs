//! Prints the methods.md §5.5 table for the simulated bar (exploration helper).
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use runout_core::grind::*;

fn main() {
    let bar = SimulatedBar::new(3.0, [0.008, -0.004], [0.0003, 0.0005]).unwrap();
    for (m, c, sigma, flutes) in [(5, 8, 0.0f64, 1), (5, 8, 0.0005, 1), (3, 4, 0.0, 1), (5, 16, 0.0005, 1), (5, 8, 0.0, 4), (3, 4, 0.0, 4)] {
        let (u, a) = uniform_grid(2.0, 28.0, m, c).unwrap();
        let edge = EdgeLine::helical_flat(6.0, flutes, 30.0, 2.0, 28.0, 2001).unwrap().rotated(18f64.to_radians());
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let trials = if sigma > 0.0 { 200 } else { 1 };
        let mut acc = [0.0; 4];
        for _ in 0..trials {
            let nd = Normal::new(0.0, sigma.max(1e-300)).unwrap();
            let grid = bar.probe(&u, &a, || if sigma > 0.0 { nd.sample(&mut rng) } else { 0.0 }).unwrap();
            let map = DeviationMap::new(&grid);
            for (k, s) in [Scheme::Bilinear, Scheme::FirstHarmonic].into_iter().enumerate() {
                let f = Interpolator::new(&map, s, RangePolicy::Clamp);
                let comp = compensate(&f, &map.axis, &edge, None).unwrap();
                let chk = grind_check(&bar, &edge, &comp);
                acc[2 * k] += chk.interpolation_rms * 1e3 / trials as f64;
                acc[2 * k + 1] += chk.interpolation_max * 1e3 / trials as f64;
            }
        }
        println!("M{m} C{c} sigma {sigma} K{flutes}: bilinear {:.3}/{:.3}  harmonic {:.4}/{:.4}", acc[0], acc[1], acc[2], acc[3]);
    }
}
