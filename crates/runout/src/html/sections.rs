//! Each report's section of the HTML page, from its serialised fields (JSON pointers in the
//! `data-key` of every number) and, for plots of data the JSON does not hold, its detail.

use super::{compare_row, fmt, Cell, Plot, Section, Table, VerdictView};
use crate::chip::CompareReport;
use crate::displacement::{AngleReport, HeightsReport, SignalReport, TeethReport};
use crate::grind::CompensateReport;
use crate::shank::{ForceReport, Thinned};
use crate::verdict::VerdictReport;
use anyhow::Result;
use runout_core::Cutter;
use runout_io::displacement_plot::{height_svg, teeth_polar_svg, HeightPlot, TeethPlot};
use runout_io::lineplot::{stacked_svg, Curve, Panel};

/// A report that has a section in the HTML page.
pub trait ToSection {
    /// Its section.
    fn section(&self) -> Result<Section>;
}

pub(super) fn kv(k: &str, v: impl std::fmt::Display) -> (String, String) {
    (k.to_string(), v.to_string())
}

fn opt(v: Option<f64>, d: usize) -> String {
    v.map_or("–".into(), |v| fmt(v, d))
}

pub(super) fn table(caption: &str, head: &[&str], rows: Vec<Vec<Cell>>) -> Table {
    Table {
        caption: caption.into(),
        head: head.iter().map(|h| h.to_string()).collect(),
        rows,
    }
}

/// Rows (quantity, value, ± SE) of a result table.
pub(super) fn row(
    name: &str,
    key: &str,
    v: f64,
    se: Option<(&str, Option<f64>)>,
    d: usize,
) -> Vec<Cell> {
    vec![
        Cell::text(name),
        Cell::num(key, v, d),
        match se {
            Some((k, s)) => Cell::opt(k, s, d),
            None => Cell::text(""),
        },
    ]
}

/// The answer first (issue 21 item 1): a table with the status, the runout and the other
/// results (each ± SE, `not identified` without a value), the reasons and warnings at the head
/// of the section's warnings.
fn answer_parts(s: &mut Section, a: &crate::answer::Answer) {
    if a.status.is_empty() {
        return; // a saved report of an earlier version: no answer
    }
    let mut rows = vec![vec![
        Cell::text("status"),
        Cell::text(&a.status),
        Cell::text(""),
    ]];
    let mut q = |name: &str, key: &str, v: Option<f64>, se_key: &str, se: Option<f64>, d| {
        rows.push(match v {
            Some(v) => row(name, key, v, Some((se_key, se)), d),
            None => vec![
                Cell::text(name),
                Cell::text("not identified"),
                Cell::text(""),
            ],
        });
    };
    if let Some(r) = &a.runout {
        q(
            "runout ρ (µm)",
            "/answer/runout/offset_um",
            r.offset_um,
            "/answer/runout/offset_um_se",
            r.offset_um_se,
            3,
        );
        if r.angle_deg.is_some() {
            q(
                "angle λ (deg)",
                "/answer/runout/angle_deg",
                r.angle_deg,
                "/answer/runout/angle_deg_se",
                r.angle_deg_se,
                1,
            );
        }
    }
    for (i, x) in a.results.iter().enumerate() {
        q(
            &format!("{} ({})", x.name, x.unit),
            &format!("/answer/results/{i}/value"),
            x.value,
            &format!("/answer/results/{i}/value_se"),
            x.value_se,
            4,
        );
    }
    s.tables.insert(
        0,
        table(
            &format!("The answer: {}", a.method),
            &["quantity", "value", "SE"],
            rows,
        ),
    );
    let mut w: Vec<String> = a.reasons.iter().chain(&a.warnings).cloned().collect();
    w.append(&mut s.warnings);
    s.warnings = w;
}

fn angle_rows(a: &AngleReport, prefix: &str) -> Vec<Vec<Cell>> {
    let k = |f: &str| format!("{prefix}/{f}");
    match a.angle_deg {
        Some(l) => vec![row(
            "angle λ (deg from tooth 0, direction of rotation)",
            &k("angle_deg"),
            l,
            Some((&k("angle_deg_se"), a.angle_deg_se)),
            2,
        )],
        None => vec![vec![
            Cell::text("angle λ (deg)"),
            Cell::text(format!(
                "{}{}",
                a.angle_status,
                a.angle_candidates_deg
                    .map_or(String::new(), |c| format!(": {:.2} or {:.2}", c[0], c[1]))
            )),
            Cell::text(a.angle_reason.clone().unwrap_or_default()),
        ]],
    }
}

pub(super) fn verdict_parts(s: &mut Section, v: &Option<VerdictReport>) {
    if let Some(v) = v {
        s.verdict = Some(VerdictView::new(v));
        s.compare = Some(compare_row(v));
        s.method.push(
            "Verdict: TIR = 2ρ against the tolerance (default ISO 15488 class 1: 10 µm TIR up to 10 mm, 15 µm above); pass when 2(ρ + 2·SE) ≤ tolerance, fail when 2(ρ − 2·SE) > tolerance, else marginal. Tooth radii R_i = |R·u(ψ_i) + e| (docs/methods.md §0, eq. 0.1); largest chip per tooth by the arc model at φ = 90° (eq. 0.4), load share h_i/Σh_j; compensated feed f_z·h_nom/h_max; slot oversize 2·(max R_i − R) (docs/methods.md §1.7).".into(),
        );
    }
}

/// The polar plot of the per-tooth deviations (µm about their mean) with the runout vector, from
/// the report's numbers: positions, the verdict's tooth radii (model), ρ and λ.
fn polar(
    positions_um: &[f64],
    v: Option<&VerdictReport>,
    offset_um: f64,
    angle_deg: Option<f64>,
    title: String,
) -> Result<Option<Plot>> {
    let b = v.map(|v| &v.basis);
    let cutter = match b.and_then(|b| b.teeth.zip(b.diameter_mm)) {
        Some((k, d)) => Some(Cutter::flat(
            d,
            k,
            b.map_or(0.0, |b| b.helix_deg).to_radians(),
        )?),
        None => None,
    };
    let z = b.map_or(0.0, |b| b.height_mm);
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len().max(1) as f64;
    let (angles, measured) = match &cutter {
        Some(c) if positions_um.len() == c.teeth() => {
            let m = mean(positions_um);
            (
                (0..c.teeth()).map(|i| c.tooth_angle(i, z)).collect(),
                positions_um.iter().map(|p| p - m).collect(),
            )
        }
        _ => (vec![], vec![]),
    };
    let model = v
        .filter(|v| !v.teeth.is_empty() && v.teeth.len() == angles.len())
        .map(|v| {
            let d: Vec<f64> = v.teeth.iter().map(|t| t.radius_deviation_um).collect();
            let m = mean(&d);
            d.iter().map(|x| x - m).collect()
        });
    let d = TeethPlot {
        tooth_angles_rad: angles,
        measured_um: measured,
        model_um: model,
        offset_um,
        angle_rad: angle_deg.map(f64::to_radians),
        title,
    };
    Ok(Some(Plot {
        id: "polar".into(),
        caption: "Per-tooth radius deviations (µm, about their mean) in the spindle frame, the first-order radius curve ρ·cos(ψ − λ) and the runout vector e (true scale); each tooth in its colour.".into(),
        svg: teeth_polar_svg(&d)?,
        shape: "square",
    }))
}

impl ToSection for TeethReport {
    fn section(&self) -> Result<Section> {
        let i = &self.input;
        let mut s = Section {
            title: "Runout from per-tooth displacement readings".into(),
            schema: self.schema.clone(),
            source: i.file.clone(),
            ..Section::default()
        };
        s.setup = vec![
            kv("readings", &i.file),
            kv("tooth numbering", &i.tooth_numbering),
            kv("teeth K", i.teeth),
            kv("diameter D (mm)", i.diameter_mm),
            kv("helix (deg)", i.helix_deg),
            kv("height above the tip (mm)", i.height_mm),
            kv(
                "sensor",
                format!(
                    "{} (beam inclination {} deg, offset {} mm)",
                    i.beam.sensor, i.beam.inclination_deg, i.beam.beam_offset_mm
                ),
            ),
            kv("noise σ_P (µm)", opt(i.noise_um, 3)),
            kv("known offset (µm)", opt(i.known_offset_um, 3)),
        ];
        let mut res = vec![row(
            "offset ρ (µm)",
            "/offset_um",
            self.offset_um,
            Some(("/offset_um_se", self.offset_um_se)),
            3,
        )];
        res.extend(angle_rows(&self.angle, ""));
        res.push(row(
            "residual rms (µm)",
            "/residual_rms_um",
            self.residual_rms_um,
            None,
            4,
        ));
        res.push(vec![
            Cell::text("degrees of freedom"),
            Cell::int("/dof", self.dof),
            Cell::text(""),
        ]);
        s.tables
            .push(table("Runout", &["quantity", "value", "± SE (1σ)"], res));
        let rows = (0..self.positions_um.len())
            .map(|t| {
                vec![
                    Cell::text(t.to_string()).tooth(t),
                    Cell::num(format!("/positions_um/{t}"), self.positions_um[t], 4),
                    Cell::opt(
                        format!("/radius_differences_um/{t}"),
                        self.radius_differences_um.get(t).copied(),
                        4,
                    ),
                ]
            })
            .collect();
        s.tables.push(table(
            "Per-tooth readings",
            &[
                "tooth",
                "tooth tip position P_i (µm)",
                "ΔR_i = P_i − P_i+1 (µm)",
            ],
            rows,
        ));
        s.plots.extend(polar(
            &self.positions_um,
            self.verdict.as_ref(),
            self.offset_um,
            self.angle.angle_deg,
            format!(
                "per-tooth radii, K = {} (runout {:.3} µm)",
                i.teeth, self.offset_um
            ),
        )?);
        s.warnings = self.notes.clone();
        s.method = vec![format!(
            "Method `{}`: radius differences ΔR_i from the tooth readings (docs/methods.md §1.2, eq. 8), (ρ, λ) by a joint least-squares fit of the exact model R_i = |R·u(ψ_i) + e| (docs/methods.md §1.5); standard errors by error propagation from the noise ({}).",
            self.method, self.noise_source
        )];
        verdict_parts(&mut s, &self.verdict);
        answer_parts(&mut s, &self.answer);
        Ok(s)
    }
}

impl ToSection for HeightsReport {
    fn section(&self) -> Result<Section> {
        let mut s = Section {
            title: "Runout at the cutting height from readings at several heights".into(),
            schema: self.schema.clone(),
            source: self.input.file.clone(),
            ..Section::default()
        };
        s.setup = vec![
            kv("table", &self.input.file),
            kv("heights", self.input.points),
            kv("regression", &self.method),
            kv("cutting height (mm)", self.at_mm),
        ];
        let mut res = vec![
            row(
                "runout at the cutting height (µm)",
                "/offset_um",
                self.offset_um,
                Some(("/offset_um_se", self.offset_um_se)),
                3,
            ),
            row(
                "slope (µm/mm)",
                "/slope_um_per_mm",
                self.slope_um_per_mm,
                Some(("/slope_um_per_mm_se", self.slope_um_per_mm_se)),
                4,
            ),
            row("R²", "/r_squared", self.r_squared, None, 4),
            row(
                "residual rms (µm)",
                "/residual_rms_um",
                self.residual_rms_um,
                None,
                4,
            ),
        ];
        if let Some(v) = &self.vector {
            res.push(row(
                "vector fit: offset (µm)",
                "/vector/offset_um",
                v.offset_um,
                Some(("/vector/offset_um_se", v.offset_um_se)),
                3,
            ));
            res.extend(angle_rows(&v.angle, "/vector"));
        }
        s.tables
            .push(table("Runout", &["quantity", "value", "± SE (1σ)"], res));
        match &self.detail.fit {
            Some(fit) => {
                let pts = &self.detail.points;
                let zs = pts.iter().map(|p| p.0).chain([fit.height_mm]);
                let (z0, z1) = zs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
                    (a.min(z), b.max(z))
                });
                let d = HeightPlot {
                    points: pts.iter().map(|(z, r)| (*z, r * 1e3)).collect(),
                    line: vec![(z0, fit.at(z0) * 1e3), (z1, fit.at(z1) * 1e3)],
                    line_label: format!("{} fit, R² = {:.4}", self.method, fit.r_squared),
                    at: (fit.height_mm, self.offset_um, self.offset_um_se),
                    title: "runout vs height (r = TIR/2)".into(),
                };
                s.plots.push(Plot {
                    id: "heights".into(),
                    caption: "Runout (half the TIR) at each height, the regression line extrapolated to the cutting height, and the result ± 2σ.".into(),
                    svg: height_svg(&d)?,
                    shape: "wide",
                });
            }
            None => s.warnings.push(
                "plot: the measured points are not in the saved JSON; run `runout displacement heights … --html` for it".into(),
            ),
        }
        s.warnings.extend(self.notes.iter().cloned());
        s.method = vec![
            "Runout r = TIR/2 at each height (seed eq. 5); r(z) by ordinary least squares (or the seed's eq. 6), extrapolated to the cutting height (docs/methods.md §1.3); with angles, the offset + tilt vector fit e(z) = e₀ + z·τ (docs/methods.md §1.6).".into(),
        ];
        verdict_parts(&mut s, &self.verdict);
        answer_parts(&mut s, &self.answer);
        Ok(s)
    }
}

impl ToSection for SignalReport {
    fn section(&self) -> Result<Section> {
        let mut s = Section {
            title: "Runout from a displacement signal".into(),
            schema: self.schema.clone(),
            source: self.input.file.clone(),
            ..Section::default()
        };
        s.setup = vec![
            kv("recording", &self.input.file),
            kv("channels", self.input.channels.join(", ")),
            kv("spindle angle from", &self.reference),
            kv("speed (rpm)", fmt(self.rpm, 3)),
            kv("revolutions", self.revolutions),
            kv(
                "section (s)",
                format!(
                    "{} – {} ({} samples)",
                    fmt(self.section.from_s, 6),
                    fmt(self.section.to_s, 6),
                    self.section.samples
                ),
            ),
        ];
        let mut res = vec![row(
            "offset ρ (µm)",
            "/offset_um",
            self.offset_um,
            Some(("/offset_um_se", Some(self.offset_um_se))),
            4,
        )];
        res.extend(angle_rows(&self.angle, ""));
        s.tables
            .push(table("Runout", &["quantity", "value", "± SE (1σ)"], res));
        let ch = self
            .channels
            .iter()
            .enumerate()
            .map(|(c, r)| {
                let k = |f: &str| format!("/channels/{c}/{f}");
                vec![
                    Cell::text(r.channel.clone()),
                    Cell::num(k("sensor_angle_deg"), r.sensor_angle_deg, 1),
                    Cell::num(k("offset_um"), r.offset_um, 4),
                    Cell::num(k("angle_deg"), r.angle_deg, 2),
                    Cell::num(k("residual_sd_um"), r.residual_sd_um, 4),
                ]
            })
            .collect();
        s.tables.push(table(
            "Channels",
            &[
                "channel",
                "sensor angle (deg)",
                "offset (µm)",
                "angle (deg)",
                "residual sd (µm)",
            ],
            ch,
        ));
        let positions = self
            .teeth
            .as_ref()
            .map_or(vec![], |t| t.positions_um.clone());
        s.plots.extend(polar(
            &positions,
            self.verdict.as_ref(),
            self.offset_um,
            self.angle.angle_deg,
            format!("runout from signal: {:.3} µm", self.offset_um),
        )?);
        s.warnings = self.notes.clone();
        s.method = vec![
            "First harmonic of the displacement against the spindle angle by linear least squares (docs/methods.md §1.5); TIR/2 per revolution (seed eq. 5); per-tooth extrema with the cutter.".into(),
        ];
        verdict_parts(&mut s, &self.verdict);
        answer_parts(&mut s, &self.answer);
        Ok(s)
    }
}

fn curve(rows: &Thinned, name: &str, c: usize) -> Curve {
    Curve {
        name: name.into(),
        points: rows.rows.iter().map(|(t, v)| (*t, v[c])).collect(),
    }
}

impl ToSection for ForceReport {
    fn section(&self) -> Result<Section> {
        let mut s = Section {
            title: "Cutting force and runout from shank deflection".into(),
            schema: self.schema.clone(),
            source: self.recording.clone(),
            ..Section::default()
        };
        let b = &self.beam;
        s.setup = vec![
            kv("recording", format!("{} ({})", self.recording, self.format)),
            kv(
                "samples",
                format!("{} at {} Hz", self.samples, fmt(self.sample_rate_hz, 1)),
            ),
            kv(
                "stiffness K_δ (N/µm)",
                format!(
                    "{} ({})",
                    fmt(self.stiffness_N_per_um, 4),
                    self.stiffness_source
                ),
            ),
            kv(
                "shank",
                format!(
                    "D {} mm, E {} GPa, tool length {} mm, sensors at {} / {} mm",
                    b.diameter_mm, b.modulus_gpa, b.tool_length_mm, b.l1_mm, b.l2_mm
                ),
            ),
            kv(
                "spindle (rpm)",
                format!(
                    "{} ± {} ({})",
                    fmt(self.spindle.rpm, 3),
                    fmt(self.spindle.rpm_se, 3),
                    self.spindle.source
                ),
            ),
            kv(
                "pairs",
                self.pairs
                    .iter()
                    .map(|p| format!("{}: {} − {}", p.axis, p.sensor_I, p.sensor_II))
                    .collect::<Vec<_>>()
                    .join("; "),
            ),
        ];
        let r = &self.runout;
        let res = vec![
            row(
                "offset at the cutting height (µm)",
                "/runout/offset_um",
                r.offset_um,
                Some(("/runout/offset_um_se", Some(r.offset_um_se))),
                3,
            ),
            row("angle (deg)", "/runout/angle_deg", r.angle_deg, None, 1),
            row(
                "cutting height above the tip (mm)",
                "/runout/at_height_above_tip_mm",
                r.at_height_above_tip_mm,
                None,
                2,
            ),
            row(
                "offset at the tip (µm)",
                "/runout/tip_offset_um",
                r.tip_offset_um,
                None,
                3,
            ),
            row(
                "tilt (µm/mm)",
                "/runout/tilt_um_per_mm",
                r.tilt_um_per_mm,
                Some(("/runout/tilt_um_per_mm_se", Some(r.tilt_um_per_mm_se))),
                4,
            ),
        ];
        s.tables
            .push(table("Runout", &["quantity", "value", "± SE (1σ)"], res));
        let f = self
            .force_over_cut
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let k = |f: &str| format!("/force_over_cut/{i}/{f}");
                vec![
                    Cell::text(format!("F{}", a.axis)),
                    Cell::num(k("mean_N"), a.mean_N, 2),
                    Cell::num(k("rms_N"), a.rms_N, 2),
                    Cell::num(k("min_N"), a.min_N, 2),
                    Cell::num(k("max_N"), a.max_N, 2),
                ]
            })
            .collect();
        s.tables.push(table(
            "Force on the workpiece over the cut",
            &["axis", "mean (N)", "rms (N)", "min (N)", "max (N)"],
            f,
        ));
        let d = &self.dynamics;
        s.tables.push(table(
            "Bandwidth",
            &["quantity", "value", ""],
            vec![
                row(
                    "first bending mode (Hz)",
                    "/dynamics/first_bending_mode_hz",
                    d.first_bending_mode_hz,
                    None,
                    0,
                ),
                row(
                    "usable bandwidth (Hz)",
                    "/dynamics/usable_bandwidth_hz",
                    d.usable_bandwidth_hz,
                    None,
                    0,
                ),
            ],
        ));
        let p = &self.plot;
        if !p.series.rows.is_empty() {
            let np = p.axes.len();
            let panels: Vec<Panel> = p
                .axes
                .iter()
                .enumerate()
                .map(|(d, a)| {
                    let mut curves = vec![curve(&p.series, &format!("F{a} shank"), d)];
                    if p.has_reference {
                        curves.push(curve(&p.series, &format!("F{a} reference"), 3 * np + d));
                    }
                    Panel {
                        y_label: format!("F{a} on workpiece (N)"),
                        curves,
                    }
                })
                .collect();
            s.plots.push(Plot {
                id: "force".into(),
                caption: "Cutting force from the shank deflection F = K_δ·(δ_II − δ_I) over the recording (thinned for the plot).".into(),
                svg: stacked_svg("Cutting force from shank deflection", "time (s)", &panels)?,
                shape: "wide",
            });
            let defl: Vec<Panel> = p
                .axes
                .iter()
                .enumerate()
                .map(|(d, a)| Panel {
                    y_label: format!("{a} deflection (µm)"),
                    curves: vec![
                        curve(&p.series, "δ_I", np + 2 * d),
                        curve(&p.series, "δ_II", np + 2 * d + 1),
                    ],
                })
                .collect();
            s.plots.push(Plot {
                id: "deflection".into(),
                caption:
                    "Shank deflections at the two sensors with the air-cut template subtracted."
                        .into(),
                svg: stacked_svg("Shank deflections δ_I, δ_II", "time (s)", &defl)?,
                shape: "wide",
            });
        } else {
            s.warnings.push(
                "plots: the time series are not in the saved JSON; run `runout shank force … --html` for them".into(),
            );
        }
        s.warnings.extend(self.warnings.iter().cloned());
        s.method = vec![
            "Force from the two-point shank deflection F = K_δ·(δ_II − δ_I) with the beam stiffness (docs/methods.md §3.1) after subtracting the angle-synchronous air-cut template (docs/methods.md §3.2); runout offset and tilt from the air-cut templates of the sensors at two heights.".into(),
        ];
        verdict_parts(&mut s, &self.verdict);
        answer_parts(&mut s, &self.answer);
        Ok(s)
    }
}

impl ToSection for CompensateReport {
    fn section(&self) -> Result<Section> {
        let i = &self.inputs;
        let mut s = Section {
            title: "Grinding compensation of the bar clamping error".into(),
            schema: self.schema.clone(),
            source: i.probe.clone(),
            ..Section::default()
        };
        s.setup = vec![
            kv("probe grid", &i.probe),
            kv("edge", &i.edge),
            kv("interpolation", &i.scheme),
            kv("outside the probed range", &i.outside_probed_range),
            kv("probe tip radius (mm)", i.probe_tip_radius_mm),
            kv("frame", &self.frame),
        ];
        let a = &self.axis;
        s.tables.push(table(
            "Bar axis",
            &["quantity", "value", ""],
            vec![
                row("offset (µm)", "/axis/offset_um", a.offset_um, None, 3),
                row(
                    "runout angle (deg)",
                    "/axis/runout_angle_deg",
                    a.runout_angle_deg,
                    None,
                    1,
                ),
                row(
                    "layer residual rms (µm)",
                    "/axis/layer_residual_rms_um",
                    a.layer_residual_rms_um,
                    None,
                    3,
                ),
            ],
        ));
        let c = &self.compensation;
        s.tables.push(table(
            "Predicted radial error of the edge",
            &["", "rms (µm)", "max (µm)"],
            vec![
                vec![
                    Cell::text("without compensation"),
                    Cell::num(
                        "/compensation/predicted_before_rms_um",
                        c.predicted_before_rms_um,
                        3,
                    ),
                    Cell::num(
                        "/compensation/predicted_before_max_um",
                        c.predicted_before_max_um,
                        3,
                    ),
                ],
                vec![
                    Cell::text("remaining after compensation"),
                    Cell::num(
                        "/compensation/predicted_remaining_rms_um",
                        c.predicted_remaining_rms_um,
                        3,
                    ),
                    Cell::num(
                        "/compensation/predicted_remaining_max_um",
                        c.predicted_remaining_max_um,
                        3,
                    ),
                ],
            ],
        ));
        let layers = self
            .layers
            .iter()
            .enumerate()
            .map(|(l, r)| {
                let k = |f: &str| format!("/layers/{l}/{f}");
                vec![
                    Cell::num(k("u_mm"), r.u_mm, 3),
                    Cell::num(k("mean_radius_mm"), r.mean_radius_mm, 4),
                    Cell::num(k("max_abs_delta_um"), r.max_abs_delta_um, 3),
                    Cell::num(k("form_rms_um"), r.form_rms_um, 3),
                ]
            })
            .collect();
        s.tables.push(table(
            "Probe layers",
            &[
                "u (mm)",
                "mean radius (mm)",
                "max |δ| (µm)",
                "form rms (µm)",
            ],
            layers,
        ));
        if let Some(map) = &self.detail.map {
            s.plots.push(Plot {
                id: "deviation_heatmap".into(),
                caption: "Deviation δ (µm) of the probed bar over height u and angle α (docs/methods.md §5.2).".into(),
                svg: runout_io::grind::plot::deviation_heatmap_svg(map)?,
                shape: "wide",
            });
        }
        let pts = |v: &[f64]| v.iter().enumerate().map(|(i, y)| (i as f64, *y)).collect();
        s.plots.push(Plot {
            id: "edge_error".into(),
            caption: "Wheel-path offset ε and the remaining radial error at every edge point (in edge order).".into(),
            svg: stacked_svg(
                "Compensation along the edge",
                "edge point (index, edge order)",
                &[
                    Panel {
                        y_label: "offset ε (µm)".into(),
                        curves: vec![Curve {
                            name: "ε".into(),
                            points: pts(&c.eps_um),
                        }],
                    },
                    Panel {
                        y_label: "remaining error (µm)".into(),
                        curves: vec![Curve {
                            name: "remaining".into(),
                            points: pts(&c.remaining_um),
                        }],
                    },
                ],
            )?,
            shape: "wide",
        });
        s.warnings = self.grid.notes.clone();
        s.method = vec![
            "Deviation per probe layer (docs/methods.md §5.2), bar axis offset + tilt by a first-harmonic fit per layer, interpolation along the edge line with periodic wrap (docs/methods.md §5.3), wheel-path offset (docs/methods.md §5.4).".into(),
        ];
        answer_parts(&mut s, &self.answer);
        Ok(s)
    }
}

impl ToSection for CompareReport {
    fn section(&self) -> Result<Section> {
        let mut s = Section {
            title: "Chip-thickness models against the exact IUCT".into(),
            schema: self.schema.clone(),
            source: self.config.clone(),
            ..Section::default()
        };
        s.setup = vec![
            kv("cases", &self.config),
            kv("mean relative error", &self.metrics.mean_relative_error),
            kv("normalised MAE", &self.metrics.normalised_mae),
            kv(
                "equivalent model",
                format!(
                    "k1 {}, k2 {}, phase refinement {}",
                    self.equivalent_model.k1,
                    self.equivalent_model.k2,
                    self.equivalent_model.phase_refinement
                ),
            ),
        ];
        let mut rows = Vec::new();
        for (c, case) in self.cases.iter().enumerate() {
            for (name, m) in case.errors_vs_exact.list() {
                let k = |f: &str| format!("/cases/{c}/errors_vs_exact/{name}/{f}");
                rows.push(vec![
                    Cell::text(case.name.clone()),
                    Cell::text(name),
                    Cell::num(
                        k("mean_relative_error_percent"),
                        m.mean_relative_error_percent,
                        3,
                    ),
                    Cell::num(k("normalised_mae_percent"), m.normalised_mae_percent, 3),
                    Cell::num(k("max_abs_error_um"), m.max_abs_error_um, 4),
                ]);
            }
        }
        for (name, m) in self.pooled.list() {
            let k = |f: &str| format!("/pooled/{name}/{f}");
            rows.push(vec![
                Cell::text("pooled"),
                Cell::text(name),
                Cell::num(
                    k("mean_relative_error_percent"),
                    m.mean_relative_error_percent,
                    3,
                ),
                Cell::num(k("normalised_mae_percent"), m.normalised_mae_percent, 3),
                Cell::num(k("max_abs_error_um"), m.max_abs_error_um, 4),
            ]);
        }
        s.tables.push(table(
            "Errors against the exact chip",
            &[
                "case",
                "model",
                "mean relative error (%)",
                "normalised MAE (%)",
                "max |error| (µm)",
            ],
            rows,
        ));
        s.warnings = self.warnings.clone();
        s.method = vec![
            "Exact instantaneous uncut chip thickness by the iterative solver (docs/methods.md §2.2) against the arc and circle models (docs/methods.md §2.3) and the equivalent model with compensation (docs/methods.md §2.4).".into(),
        ];
        Ok(s)
    }
}

/// The section of a saved **identify** report (`runout report id.json …`): the identify report
/// types are not deserialisable as a whole (they hold core types), so the saved JSON is read for
/// what the page and the comparison need — the answer (runout ± SE, status, reasons, warnings),
/// the set-up and the verdict (judged again at `tolerance_tir_um`). The plots are not in the JSON:
/// the page says to use `runout identify … --html` for them.
pub(super) fn saved_identify(
    v: &serde_json::Value,
    name: &str,
    tolerance_tir_um: Option<f64>,
) -> Result<Section> {
    use anyhow::Context;
    let answer = v
        .get("answer")
        .with_context(|| format!("{name}: no `answer` (expected runout.identify.recording/3)"))?;
    let verdict: Option<VerdictReport> = match v.get("verdict") {
        Some(x) if !x.is_null() => Some(
            serde_json::from_value::<VerdictReport>(x.clone())
                .with_context(|| format!("{name}: `verdict` is not a verdict"))?
                .with_tolerance(tolerance_tir_um.or(x["tolerance_tir_um"].as_f64()))?,
        ),
        _ => None,
    };
    let num = |p: &str| v.pointer(p).and_then(serde_json::Value::as_f64);
    let mut s = Section {
        title: "Runout and cutting coefficients from force recordings".into(),
        schema: v["schema"].as_str().unwrap_or_default().to_string(),
        source: format!("saved report {name}"),
        ..Section::default()
    };
    let files: Vec<String> = v["recordings"]
        .as_array()
        .map(|r| {
            r.iter()
                .filter_map(|x| x["file"].as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    s.setup = vec![
        kv("recordings", files.join(", ")),
        kv(
            "cutter",
            format!(
                "K {}, D {} mm, helix {}°",
                v["inputs"]["teeth"],
                opt(num("/inputs/diameter_mm"), 3),
                opt(num("/inputs/helix_deg"), 1)
            ),
        ),
        kv("method", answer["method"].as_str().unwrap_or("–")),
        kv("status", answer["status"].as_str().unwrap_or("–")),
    ];
    let r = &answer["runout"];
    let mut rows = Vec::new();
    if let Some(rho) = r["offset_um"].as_f64() {
        rows.push(row(
            "runout ρ (µm)",
            "/answer/runout/offset_um",
            rho,
            Some(("/answer/runout/offset_um_se", r["offset_um_se"].as_f64())),
            2,
        ));
    }
    if let Some(l) = r["angle_deg"].as_f64() {
        rows.push(row(
            "angle λ (deg, from tooth 0 in the rotation direction)",
            "/answer/runout/angle_deg",
            l,
            Some(("/answer/runout/angle_deg_se", r["angle_deg_se"].as_f64())),
            1,
        ));
    }
    s.tables.push(Table {
        caption: "The answer".into(),
        head: vec!["quantity".into(), "value".into(), "SE".into()],
        rows,
    });
    for key in ["reasons", "warnings"] {
        for w in answer[key].as_array().into_iter().flatten() {
            if let Some(w) = w.as_str() {
                s.warnings.push(w.to_string());
            }
        }
    }
    s.warnings.push(
        "plots: the averaged waveforms are not in the saved JSON; run `runout identify … --html` for them"
            .into(),
    );
    s.method.push(
        "Runout and coefficients from the full-signal fit of the averaged force waveforms of all recordings jointly, through the measuring chain (docs/methods.md §4.5–4.7); the per-tooth-peak sine fits are cross-checks (docs/methods.md §4.2).".into(),
    );
    verdict_parts(&mut s, &verdict);
    Ok(s)
}
