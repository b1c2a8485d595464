//! Write a synthetic shank-sensor recording (CSV) for trying and benchmarking
//! `runout shank force`: 4 displacement channels (µm) at 100 kHz by default, plus the true force
//! as reference channels.
//!
//! `cargo run --release -p runout-cli --example shank_recording -- OUT.csv [CUT_REVOLUTIONS] [RATE_HZ] [MODE_HZ]`
//! (then `runout shank force OUT.csv --config crates/runout-cli/tests/data/shank.toml`).
//! `MODE_HZ` puts a bending mode (Hz, damping 0.03) between force and deflections on both axes,
//! `beam` the beam model's own first mode (steel, 1370 Hz for this tool); default rigid.

use runout_core::chain::{AxisChain, MeasuringChain, SensorMode};
use runout_core::shank::{ShankBeam, SyntheticShank, STEEL_DENSITY_KG_PER_M3};
use runout_core::*;
use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = args
        .get(1)
        .ok_or("usage: shank_recording OUT.csv [CUT_REVOLUTIONS] [RATE_HZ] [MODE_HZ|beam]")?;
    let cut: f64 = args.get(2).map_or(Ok(300.0), |s| s.parse())?;
    let rate: f64 = args.get(3).map_or(Ok(100_000.0), |s| s.parse())?;
    let beam = ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0)?;
    let chain = match args.get(4).map(String::as_str) {
        None => MeasuringChain::default(),
        Some(m) => {
            let hz = if m == "beam" {
                beam.first_bending_mode_hz(STEEL_DENSITY_KG_PER_M3)?
            } else {
                m.parse()?
            };
            let axis = AxisChain::Modes(vec![SensorMode::new(hz, 0.03, 1.0)?]);
            MeasuringChain {
                x: axis.clone(),
                y: axis,
                z: AxisChain::Rigid,
            }
        }
    };
    let cutter = Cutter::flat(8.0, 3, 30.0f64.to_radians())?;
    let runout = Runout::new(0.010, 30f64.to_radians())?;
    let c = Cut::new(3000.0, 0.05, 2.0)?.radial(2.0, MillingMode::Down, &cutter)?;
    let coefficients = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1])?;
    let chip = ArcChip::new(&cutter, &runout, 0.05)?;
    let model = ForceModel {
        cutter,
        runout,
        cut: c,
        coefficients,
    };
    let series = model.simulate(&chip, &Sampling::new(1.0, 0.2, 20)?);
    let syn = SyntheticShank {
        beam,
        sample_rate_hz: rate,
        rpm: 3000.0 * 1.001,
        revolutions: (20.0, cut, 20.0),
        offset_mm: (0.010 * 0.7f64.cos(), 0.010 * 0.7f64.sin()),
        tilt: (0.0002 * 2.1f64.cos(), 0.0002 * 2.1f64.sin()),
        form_mm: (0.0015, 0.0005),
        gap_mm: (0.5, 0.48),
        drift_mm: 0.0005,
        ramp_revolutions: 2.0,
        pulse: false,
        chain,
    };
    // xorshift + Box–Muller: 0.05 µm Gaussian sensor noise, reproducible
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut noise = move || {
        let (u1, u2) = (uniform().max(1e-300), uniform());
        5e-5 * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    };
    let rec = syn.generate(&series.fx, &series.fy, &mut noise);
    let mut w = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(out)?);
    writeln!(w, "time_s,xI_um,xII_um,yI_um,yII_um,Fx_N,Fy_N")?;
    for k in 0..rec.force_n[0].len() {
        writeln!(
            w,
            "{:.6},{:.4},{:.4},{:.4},{:.4},{:.3},{:.3}",
            k as f64 / rate,
            rec.columns[0][k] * 1e3,
            rec.columns[1][k] * 1e3,
            rec.columns[2][k] * 1e3,
            rec.columns[3][k] * 1e3,
            rec.force_n[0][k],
            rec.force_n[1][k]
        )?;
    }
    w.flush()?;
    eprintln!(
        "wrote {out}: {} samples, cut samples {}..{}",
        rec.force_n[0].len(),
        rec.cut.0,
        rec.cut.1
    );
    Ok(())
}
