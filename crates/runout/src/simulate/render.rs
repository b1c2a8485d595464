//! `simulate` as text, CSV, a DynoWare recording and a plot — all from the report.

use super::{SimulateReport, OVERSAMPLE};
use anyhow::{Context, Result};
use runout_io::export::{write_dynoware, Channel, TextStyle};
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// The human-readable summary.
pub fn text(r: &SimulateReport) -> String {
    let i = &r.inputs;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "runout simulate: K = {}, D = {} mm, {} rpm, f_z = {} mm, a_p = {} mm, runout {:.2} µm at {:.1}°",
        i.teeth, i.diameter_mm, i.rpm, i.fz_mm, i.ap_mm, i.runout_um, i.runout_angle_deg
    );
    let _ = writeln!(
        s,
        "{} samples; mean F_x {:.2} N, F_y {:.2} N, F_z {:.2} N, torque {:.4} N·m",
        r.samples, r.mean_fx_N, r.mean_fy_N, r.mean_fz_N, r.mean_torque_Nm
    );
    let _ = writeln!(
        s,
        "tooth  peak |F_xy| (N)  at spindle angle (deg)  max chip (µm)"
    );
    for p in &r.tooth_peaks {
        let _ = writeln!(
            s,
            "{:>5}  {:>16.3}  {:>22.2}  {:>13.3}",
            p.tooth,
            p.peak_fxy_N,
            p.spindle_angle_deg,
            p.max_chip_mm * 1e3
        );
    }
    s
}

/// The force time series as CSV: `time_s, angle_deg, fx_N, fy_N, fz_N, torque_Nm, h<i>_mm`.
pub fn forces_csv(mut w: impl Write, r: &SimulateReport) -> Result<()> {
    let s = &r.detail.series;
    let k = s.chip.len();
    write!(w, "time_s,angle_deg,fx_N,fy_N,fz_N,torque_Nm")?;
    for i in 0..k {
        write!(w, ",h{i}_mm")?;
    }
    writeln!(w)?;
    for q in 0..s.len() {
        write!(
            w,
            "{:.9},{:.4},{:.6},{:.6},{:.6},{:.6}",
            s.time[q],
            s.angle[q].to_degrees(),
            s.fx[q],
            s.fy[q],
            s.fz[q],
            s.torque[q]
        )?;
        for i in 0..k {
            write!(w, ",{:.7}", s.chip[i][q])?;
        }
        writeln!(w)?;
    }
    w.flush()?;
    Ok(())
}

/// The recording as a Kistler DynoWare text export (channels Fx, Fy, Fz in N); `file_name`
/// is the name written in its header (`.txt` becomes `.dwd`, as DynoWare names its data).
pub fn recording(
    mut w: impl Write,
    r: &SimulateReport,
    file_name: &str,
    style: TextStyle,
) -> Result<()> {
    let rec = r
        .detail
        .recording
        .as_ref()
        .context("no recording was simulated (give the recording options in the request)")?;
    let name = file_name.replace(".txt", ".dwd");
    let noise = format!(
        "{}% of peak |F_xy| ({:.3} N)",
        rec.noise_percent, rec.noise_sigma_N
    );
    let sensor_text = rec.sensor.as_ref().map_or_else(
        || "rigid".to_string(),
        |d| {
            format!(
                "{d} - cut simulated {OVERSAMPLE}x oversampled then filtered and decimated - noise after the sensor"
            )
            // the header line must stay one field whatever the delimiter
            .replace([',', ';', '\t'], " ")
        },
    );
    let meta = [
        ("Filename", name.as_str()),
        ("Cycle No", "1"),
        ("Comment", "simulated by runout simulate"),
        ("Noise", noise.as_str()),
        ("Sensor", sensor_text.as_str()),
    ];
    let chans = [("Fx", &rec.fx), ("Fy", &rec.fy), ("Fz", &rec.fz)].map(|(name, data)| Channel {
        name,
        unit: "N",
        data,
    });
    write_dynoware(&mut w, rec.sample_rate_hz, &meta, &chans, style)?;
    w.flush()?;
    Ok(())
}

/// Forces vs spindle angle with each tooth's peak marked (.svg or .png).
pub fn plot(path: &Path, r: &SimulateReport) -> Result<()> {
    runout_io::plot::force_plot(
        path,
        &r.detail.series,
        &r.detail.peaks,
        "runout simulate: forces on the workpiece",
    )?;
    Ok(())
}
