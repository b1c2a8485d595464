//! Shank force as a library call: a recording and its config held in memory (as a Python
//! binding or a distributed engine would pass them), `runout::shank::force`, typed report.
//!
//! `cargo run --release -p runout --example shank_force`

use runout::core::shank::{ShankBeam, SyntheticShank};
use runout::core::{
    ArcChip, Cut, Cutter, CuttingCoefficients, ForceModel, MillingMode, Runout, Sampling,
};
use runout::shank::{force, ForceReport, ForceRequest};
use runout::{NoProgress, Source};

const CONFIG: &str = r#"
[shank]
modulus_gpa = 210
diameter_mm = 8
tool_length_mm = 65
l1_mm = 10
l2_mm = 30
axial_depth_mm = 2
[spindle]
rpm = 3000
[[pair]]
axis = "x"
sensor_I = "xI"
sensor_II = "xII"
[[pair]]
axis = "y"
sensor_I = "yI"
sensor_II = "yII"
"#;

/// A synthetic recording (20 kHz CSV, µm) of a 3-tooth cut with 10 µm runout, then its report.
pub fn run() -> anyhow::Result<ForceReport> {
    force(&request()?, &mut NoProgress)
}

/// The request: recording and config as bytes in memory.
pub fn request() -> anyhow::Result<ForceRequest> {
    let cutter = Cutter::flat(8.0, 3, 30.0f64.to_radians())?;
    let runout = Runout::new(0.010, 0.5)?;
    let cut = Cut::new(3000.0, 0.05, 2.0)?.radial(2.0, MillingMode::Down, &cutter)?;
    let chip = ArcChip::new(&cutter, &runout, 0.05)?;
    let coefficients = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1])?;
    let model = ForceModel {
        cutter,
        runout,
        cut,
        coefficients,
    };
    let forces = model.simulate(&chip, &Sampling::new(1.0, 0.5, 10)?);
    let shank = SyntheticShank {
        beam: ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0)?,
        sample_rate_hz: 20_000.0,
        rpm: 3000.0,
        revolutions: (10.0, 20.0, 10.0),
        offset_mm: (0.010 * 0.7f64.cos(), 0.010 * 0.7f64.sin()),
        tilt: (0.0, 0.0),
        form_mm: (0.0015, 0.0005),
        gap_mm: (0.5, 0.48),
        drift_mm: 0.0,
        ramp_revolutions: 2.0,
        pulse: false,
        chain: Default::default(),
    };
    let rec = shank.generate_with_random_force(&forces.fx, &forces.fy, 0.0, || 0.0);
    let mut csv = String::from("time_s,xI_um,xII_um,yI_um,yII_um\n");
    for k in 0..rec.columns[0].len() {
        csv += &format!("{:.6}", k as f64 / 20_000.0);
        for c in &rec.columns {
            csv += &format!(",{:.5}", c[k] * 1e3);
        }
        csv.push('\n');
    }
    Ok(ForceRequest::new(
        Source::bytes("synthetic.csv", csv.into_bytes()),
        Source::bytes("shank.toml", CONFIG.as_bytes()),
    ))
}

fn main() -> anyhow::Result<()> {
    let r = run()?;
    println!(
        "runout at the tip {:.2} µm at {:.1}°, tilt {:.3} µm/mm",
        r.runout.tip_offset_um, r.runout.tip_angle_deg, r.runout.tilt_um_per_mm
    );
    for f in &r.force_over_cut {
        println!("F{}: mean {:.1} N, rms {:.1} N", f.axis, f.mean_N, f.rms_N);
    }
    Ok(())
}
