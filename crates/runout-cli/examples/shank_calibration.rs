//! Write a synthetic static-calibration recording (CSV) for trying `runout shank calibrate`: a load
//! cell (`load_N`) pushing the tool at three load points (`a_mm`, from the holder face) in steps of
//! 0–100 N, and the two x sensors (`xI_um`, `xII_um`) of `examples/shank/shank.toml`. The true
//! shank is the beam of that config held by a holder of k_θ = 20 kN·m/rad, so the calibrated
//! stiffness is lower than the beam formula's.
//!
//! `cargo run --release -p runout-cli --example shank_calibration -- examples/shank/calibration.csv`

use runout_core::shank::{LoadPoint, ShankBeam};
use std::fmt::Write as _;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .ok_or("usage: shank_calibration OUT.csv")?;
    let held = ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0)?.with_holder_stiffness(2e7)?;
    let mut s = String::from("load_N,a_mm,xI_um,xII_um\n");
    let mut k = 0u64;
    for a in [40.0, 52.0, 64.0] {
        let at = held.with_load_point(LoadPoint::At { distance_mm: a })?;
        for f in [0.0, 25.0, 50.0, 75.0, 100.0] {
            for _ in 0..20 {
                // LCG: uniform sensor noise of ±0.01 µm, reproducible
                k = k
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let noise = ((k >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02;
                let d1 = at.compliance_at_mm_per_n(10.0) * f * 1e3 + 3.0;
                let d2 = at.compliance_at_mm_per_n(30.0) * f * 1e3 + 5.0 + noise;
                writeln!(s, "{f},{a},{d1:.5},{d2:.5}")?;
            }
        }
    }
    std::fs::write(&out, s)?;
    eprintln!("wrote {out}");
    Ok(())
}
