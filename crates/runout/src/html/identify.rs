//! The section of `identify RECORDING…` (`runout.identify.recording/1`): set-up, verdict,
//! runout ρ ± SE and λ ± SE on a polar plot with the teeth, measured vs predicted waveforms,
//! per-tooth peaks, the coefficients ± SE, fit quality, every warning.

use super::sections::{kv, row, table, ToSection};
use super::{fmt, Cell, Plot, Section};
use crate::identify::{Fitted, RecordingsReport};
use anyhow::Result;
use runout_io::plot::identify::{
    runout_polar_svg, tooth_peak_bars_svg, waveform_overlay_svg, Curve, RunoutMark,
};

fn file_label(file: &str) -> String {
    std::path::Path::new(file)
        .file_name()
        .map_or(file.to_string(), |n| n.to_string_lossy().into_owned())
}

impl ToSection for RecordingsReport {
    fn section(&self) -> Result<Section> {
        let i = &self.inputs;
        let files: Vec<String> = self.recordings.iter().map(|r| r.file.clone()).collect();
        let mut s = Section {
            title: "Runout and cutting coefficients from force recordings".into(),
            schema: self.schema.clone(),
            source: files.join(", "),
            ..Section::default()
        };
        s.setup = vec![
            kv(
                "cutter",
                format!(
                    "K = {}, D = {} mm, helix {} deg",
                    i.teeth,
                    i.diameter_mm,
                    fmt(i.helix_deg, 2)
                ),
            ),
            kv("peak component", &i.peak_component),
            kv(
                "measuring chain",
                format!(
                    "{} (requested {}): {}",
                    self.measuring_chain.decision.used,
                    self.measuring_chain.decision.requested,
                    self.measuring_chain.decision.reason
                ),
            ),
            kv("conventions", &self.conventions),
        ];
        let recs = self
            .recordings
            .iter()
            .enumerate()
            .map(|(n, r)| {
                let k = |f: &str| format!("/recordings/{n}/{f}");
                vec![
                    Cell::text(file_label(&r.file)),
                    Cell::text(r.axes.clone()),
                    Cell::num(k("fz_mm"), r.fz_mm, 3),
                    Cell::num(k("ap_mm"), r.ap_mm, 2),
                    Cell::text(format!("{}–{}", fmt(r.entry_deg, 1), fmt(r.exit_deg, 1))),
                    Cell::num(k("spindle/rpm"), r.spindle.rpm, 1),
                    Cell::num(k("sample_rate_hz"), r.sample_rate_hz, 0),
                    Cell::int(k("revolutions_averaged"), r.revolutions_averaged),
                ]
            })
            .collect();
        s.tables.push(table(
            "Recordings",
            &[
                "file",
                "axes (sensor → workpiece)",
                "f_z (mm)",
                "a_p (mm)",
                "immersion (deg)",
                "speed (rpm)",
                "sample rate (Hz)",
                "revolutions averaged",
            ],
            recs,
        ));
        let mut marks: Vec<(String, f64, f64, f64, f64)> = Vec::new();
        match &self.full_signal {
            Fitted::Fit(f) => {
                s.tables.push(table(
                    "Runout (full-signal fit of all recordings)",
                    &["quantity", "value", "± SE (1σ)"],
                    vec![
                        row(
                            "offset ρ (µm)",
                            "/full_signal/offset_um",
                            f.offset_um,
                            Some(("/full_signal/offset_um_se", f.offset_um_se)),
                            3,
                        ),
                        row(
                            "angle λ (deg from tooth 0, direction of rotation)",
                            "/full_signal/angle_deg",
                            f.angle_deg,
                            Some(("/full_signal/angle_deg_se", f.angle_deg_se)),
                            2,
                        ),
                        row("R²", "/full_signal/r_squared", f.r_squared, None, 5),
                        row(
                            "residual rms (N)",
                            "/full_signal/residual_rms_N",
                            f.residual_rms_N,
                            None,
                            3,
                        ),
                        row(
                            "condition number",
                            "/full_signal/condition",
                            f.condition,
                            None,
                            1,
                        ),
                    ],
                ));
                let c = &f.coefficients;
                let names = [
                    ("K_tc (N/mm²)", "ktc_N_per_mm2"),
                    ("K_rc (N/mm²)", "krc_N_per_mm2"),
                    ("K_ac (N/mm²)", "kac_N_per_mm2"),
                    ("K_te (N/mm)", "kte_N_per_mm"),
                    ("K_re (N/mm)", "kre_N_per_mm"),
                    ("K_ae (N/mm)", "kae_N_per_mm"),
                ];
                let rows = names
                    .iter()
                    .zip(c.all())
                    .map(|((n, k), (v, se))| {
                        row(
                            n,
                            &format!("/full_signal/coefficients/{k}"),
                            v,
                            Some((&format!("/full_signal/coefficients/{k}_se"), se)),
                            2,
                        )
                    })
                    .collect();
                s.tables.push(table(
                    "Cutting coefficients",
                    &["coefficient", "value", "± SE (1σ)"],
                    rows,
                ));
                s.warnings.extend(f.warnings.iter().cloned());
                marks.push((
                    "full-signal fit".into(),
                    f.offset_um,
                    f.angle_deg,
                    f.offset_um_se.unwrap_or(f64::NAN),
                    f.angle_deg_se.unwrap_or(f64::NAN),
                ));
            }
            Fitted::Failed { error } => s.warnings.push(format!("full-signal fit failed: {error}")),
        }
        for (n, r) in self.recordings.iter().enumerate() {
            let rows = r
                .tooth_peaks
                .iter()
                .enumerate()
                .map(|(t, p)| {
                    let k = |f: &str| format!("/recordings/{n}/tooth_peaks/{t}/{f}");
                    vec![
                        Cell::int(k("tooth"), p.tooth).tooth(p.tooth),
                        Cell::num(k("peak_N"), p.peak_N, 2),
                        Cell::num(k("peak_N_se"), p.peak_N_se, 2),
                        Cell::num(k("spindle_angle_deg"), p.spindle_angle_deg, 1),
                    ]
                })
                .collect();
            s.tables.push(table(
                &format!(
                    "Per-tooth peaks of {} ({})",
                    file_label(&r.file),
                    r.peak_component
                ),
                &["tooth", "peak (N)", "± SE (N)", "spindle angle (deg)"],
                rows,
            ));
            if let Fitted::Fit(f) = &r.sine_fit {
                marks.push((
                    format!("sine fit {}", file_label(&r.file)),
                    f.offset_um,
                    f.angle_deg,
                    f.offset_um_se.unwrap_or(f64::NAN),
                    f.angle_deg_se.unwrap_or(f64::NAN),
                ));
            }
            s.warnings.extend(
                r.warnings
                    .iter()
                    .map(|w| format!("{}: {w}", file_label(&r.file))),
            );
        }
        let rm: Vec<RunoutMark> = marks
            .iter()
            .map(|(l, o, a, os, as_)| RunoutMark {
                label: l,
                offset_um: *o,
                angle_deg: *a,
                offset_um_se: *os,
                angle_deg_se: *as_,
            })
            .collect();
        if !rm.is_empty() {
            s.plots.push(Plot {
                id: "polar".into(),
                caption: "Runout vector of every estimate with its ±1 SE sector, tooth directions marked (deg from tooth 0 in the direction of rotation).".into(),
                svg: runout_polar_svg(&rm, i.teeth, "runout ρ, λ (µm, deg)")?,
                shape: "square",
            });
        }
        let label = ["F_x (N)", "F_y (N)", "F_z (N)"];
        for (n, w) in self.waveforms.iter().enumerate() {
            let Some(pred) = &w.predicted_N else { continue };
            fn c<'a>(v: &'a [Vec<f64>; 3], n: usize, label: &[&'static str; 3]) -> Vec<Curve<'a>> {
                (0..n)
                    .map(|j| Curve {
                        label: label[j],
                        values: &v[j],
                    })
                    .collect()
            }
            let rec = &self.recordings[n];
            s.plots.push(Plot {
                id: format!("waveform_{n}"),
                caption: format!("{}: averaged force over one revolution (solid) against the full-signal model (dashed).", file_label(&rec.file)),
                svg: waveform_overlay_svg(&w.angle_deg, &c(&w.measured_N, w.components, &label), &c(pred, w.components, &label), &format!("{}: measured vs model", file_label(&rec.file)))?,
                shape: "wide",
            });
            if let Fitted::Fit(f) = &rec.sine_fit {
                let p: Vec<f64> = rec.tooth_peaks.iter().map(|p| p.peak_N).collect();
                let se: Vec<f64> = rec.tooth_peaks.iter().map(|p| p.peak_N_se).collect();
                s.plots.push(Plot {
                    id: format!("tooth_peaks_{n}"),
                    caption: format!(
                        "{}: per-tooth peaks ±1 SE with the fitted sine (docs/methods.md §4.2).",
                        file_label(&rec.file)
                    ),
                    svg: tooth_peak_bars_svg(
                        &p,
                        &se,
                        f.mean_N,
                        f.amplitude_N,
                        f.phase_deg.to_radians(),
                        &format!("{}: per-tooth peaks", file_label(&rec.file)),
                    )?,
                    shape: "wide",
                });
            }
        }
        if let Some(c) = &self.consistency {
            s.warnings.extend(c.warnings.iter().cloned());
        }
        s.warnings.extend(self.status.fit.iter().cloned());
        for p in &self.status.parameters {
            s.warnings.push(format!(
                "{}: {}{}",
                p.parameter,
                p.status,
                p.reason
                    .as_ref()
                    .map_or(String::new(), |r| format!(" — {r}"))
            ));
        }
        s.warnings
            .extend(self.radius_difference_warnings.iter().cloned());
        s.method = vec![
            "Spindle speed measured, steady cut detected, synchronous average over whole revolutions; per-tooth peaks with the seed-003 sine fit F_i = C + A·sin(φ + 2πi/K) (docs/methods.md §4.2); mean-force calibration of the cutting coefficients over ≥ 2 feeds (docs/methods.md §4.4); full-signal fit of all recordings jointly through the measuring chain (docs/methods.md §4.7), standard errors from the fit's covariance.".into(),
        ];
        super::sections::verdict_parts(&mut s, &self.verdict);
        Ok(s)
    }
}
