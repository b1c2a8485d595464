//! The README's main job as a library call: two force recordings → runout and coefficients.
//! `cargo run --release -p runout --example identify`
use runout::core::{Cut, Cutter, MillingMode};
use runout::identify::{recordings, RecordingsReport, RecordingsRequest};
use runout::{NoProgress, Source};

/// Runout and coefficients from the bundled recordings (examples/identify, f_z 0.05, 0.08 mm).
pub fn run() -> anyhow::Result<RecordingsReport> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/identify");
    let cutter = Cutter::flat(10.0, 4, 30f64.to_radians())?; // D (mm), K, helix (rad)
    let (mut sources, mut cuts) = (Vec::new(), Vec::new());
    for fz in [0.05, 0.08] {
        sources.push(Source::path(format!("{dir}/cut_fz{fz}.txt")));
        cuts.push(Cut::new(3240.0, fz, 2.0)?.radial(2.0, MillingMode::Down, &cutter)?);
    }
    recordings(
        &RecordingsRequest::new(sources, cutter, cuts),
        &mut NoProgress,
    )
}

fn main() -> anyhow::Result<()> {
    let r = run()?;
    let f = r
        .full_signal
        .ok()
        .ok_or(anyhow::anyhow!("full-signal fit failed"))?;
    let se = |s: Option<f64>| s.unwrap_or(f64::NAN);
    println!("ρ = {:.2} ± {:.2} µm", f.offset_um, se(f.offset_um_se));
    println!("λ = {:.1} ± {:.1}°", f.angle_deg, se(f.angle_deg_se));
    let names = ["K_tc", "K_rc", "K_ac", "K_te", "K_re", "K_ae"];
    for (name, (k, s)) in names.iter().zip(f.coefficients.all()) {
        println!("{name} = {k:.1} ± {:.1}", se(s));
    }
    Ok(())
}
