//! The engineer's report (issue 15): one self-contained HTML file per report, or several reports
//! in one page with a comparison table — the verdict and its consequences first, then the set-up,
//! the results, the plots (inline SVG), the warnings and how it was computed. Inline CSS (print
//! CSS for A4), no script, no font or image from the network.
//!
//! The page is an [askama] template checked at compile time (`templates/report.html`; escaping
//! on: every text is escaped, only the SVG the plotting code drew is inserted as is — plotters
//! escapes the text inside it). The content comes from the **serialised fields** of the typed
//! reports, so `--html` and `runout report saved.json` show the same numbers; plots that need
//! data the JSON does not hold (time series, measured points) are drawn when the report comes
//! fresh from the job and are said to be missing otherwise.
//!
//! Every number shown from the report carries `data-key` (its JSON pointer in the report) and
//! `data-value` (the value as the JSON writes it: shortest round-trip form), so a test — or a
//! reader's script — can check the page against the JSON.
//!
//! Why here and not in its own crate: the page is built from the report types of this crate
//! and their plots; a separate crate would need all of them public for nothing else.

mod identify;
mod sections;

use crate::verdict::VerdictReport;
use anyhow::{bail, Context, Result};
use askama::Template;
use runout_io::plot::tooth_hex;
use serde_json::Value;

pub use sections::ToSection;

/// One table cell: the text shown; for a number from the report, its JSON pointer and value.
#[derive(Debug, Clone, Default)]
pub struct Cell {
    /// Shown text.
    pub text: String,
    /// CSS class (`n` for numbers).
    pub class: &'static str,
    /// JSON pointer of the value in the report (`/verdict/tir_um`).
    pub key: Option<String>,
    /// The value as the JSON writes it.
    pub value: String,
    /// Colour swatch (a tooth's colour).
    pub swatch: Option<String>,
}

impl Cell {
    /// A text cell.
    pub fn text(t: impl Into<String>) -> Self {
        Self {
            text: t.into(),
            ..Self::default()
        }
    }

    /// A number from the report at JSON pointer `key`, shown with `decimals`.
    pub fn num(key: impl Into<String>, v: f64, decimals: usize) -> Self {
        Self {
            text: fmt(v, decimals),
            class: "n",
            key: Some(key.into()),
            value: json_number(v),
            swatch: None,
        }
    }

    /// An optional number (`–` when absent).
    pub fn opt(key: impl Into<String>, v: Option<f64>, decimals: usize) -> Self {
        match v {
            Some(v) => Self::num(key, v, decimals),
            None => Self {
                text: "–".into(),
                class: "n",
                ..Self::default()
            },
        }
    }

    /// An integer from the report.
    pub fn int(key: impl Into<String>, v: usize) -> Self {
        Self {
            text: v.to_string(),
            class: "n",
            key: Some(key.into()),
            value: v.to_string(),
            swatch: None,
        }
    }

    /// With tooth `i`'s colour swatch.
    pub fn tooth(mut self, i: usize) -> Self {
        self.swatch = Some(tooth_hex(i));
        self
    }
}

/// A number with `decimals` (non-finite: `–`).
pub fn fmt(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        "–".into()
    }
}

/// A number as the JSON writes it (shortest round trip; `null` when not finite).
pub fn json_number(v: f64) -> String {
    serde_json::to_string(&Value::from(v)).unwrap_or_else(|_| "null".into())
}

/// A table with a caption.
#[derive(Debug, Clone, Default)]
pub struct Table {
    /// Caption (h3).
    pub caption: String,
    /// Column heads (with units).
    pub head: Vec<String>,
    /// Rows.
    pub rows: Vec<Vec<Cell>>,
}

/// An inline SVG plot.
#[derive(Debug, Clone)]
pub struct Plot {
    /// Identifier (`polar`, `force`, …), unique in a section.
    pub id: String,
    /// Caption.
    pub caption: String,
    /// The SVG document.
    pub svg: String,
    /// `square` for polar plots (narrower), else `wide`.
    pub shape: &'static str,
}

/// The verdict block.
#[derive(Debug, Clone)]
pub struct VerdictView {
    /// `pass`, `marginal`, `fail` (CSS class).
    pub status: String,
    /// `PASS`, …
    pub status_word: String,
    /// Findings in words.
    pub findings: Vec<String>,
    /// Per-tooth table.
    pub teeth: Table,
}

impl VerdictView {
    /// From the report's verdict (at JSON pointer `/verdict`).
    pub fn new(v: &VerdictReport) -> Self {
        let mut teeth = Table {
            caption: String::new(),
            head: vec![
                "tooth".into(),
                "actual radius R_i (mm)".into(),
                "R_i − R (µm)".into(),
                "max chip h_i (µm)".into(),
                "load share (%)".into(),
            ],
            rows: vec![],
        };
        for (i, t) in v.teeth.iter().enumerate() {
            let k = |f: &str| format!("/verdict/teeth/{i}/{f}");
            let mut share = Cell::opt(k("load_share"), t.load_share, 4);
            if let Some(s) = t.load_share {
                share.text = fmt(100.0 * s, 1);
            }
            teeth.rows.push(vec![
                Cell::int(k("tooth"), t.tooth).tooth(t.tooth),
                Cell::num(k("radius_mm"), t.radius_mm, 4),
                Cell::num(k("radius_deviation_um"), t.radius_deviation_um, 2),
                Cell::opt(k("max_chip_um"), t.max_chip_um, 2),
                share,
            ]);
        }
        Self {
            status: v.status.clone(),
            status_word: v.status.to_uppercase(),
            findings: v.findings.clone(),
            teeth,
        }
    }
}

/// One report's part of the page.
#[derive(Debug, Clone, Default)]
pub struct Section {
    /// Heading.
    pub title: String,
    /// The report's `schema`.
    pub schema: String,
    /// The input file (or the saved JSON).
    pub source: String,
    /// The verdict, for reports that identify a runout.
    pub verdict: Option<VerdictView>,
    /// Set-up: (name with unit, value).
    pub setup: Vec<(String, String)>,
    /// Result tables.
    pub tables: Vec<Table>,
    /// Plots.
    pub plots: Vec<Plot>,
    /// Warnings and notes, in words.
    pub warnings: Vec<String>,
    /// How it was computed (method, equations with their `methods.md §` section).
    pub method: Vec<String>,
    /// The row of the comparison table, for reports with a verdict.
    pub compare: Option<Vec<Cell>>,
}

#[derive(Template)]
#[template(path = "report.html", escape = "html")]
struct Page<'a> {
    title: &'a str,
    subtitle: &'a str,
    generator: String,
    comparison: Option<Table>,
    sections: &'a [Section],
}

/// The whole page for `sections` (a comparison table when two or more have a verdict).
pub fn page(title: &str, sections: &[Section]) -> Result<String> {
    let rows: Vec<Vec<Cell>> = sections
        .iter()
        .filter_map(|s| {
            s.compare.clone().map(|mut row| {
                row.insert(0, Cell::text(s.source.clone()));
                row.insert(1, Cell::text(s.schema.clone()));
                row
            })
        })
        .collect();
    let comparison = (rows.len() >= 2).then(|| Table {
        caption: "Comparison".into(),
        head: [
            "source",
            "job",
            "runout ρ (µm)",
            "SE (µm)",
            "angle λ (deg)",
            "TIR 2ρ (µm)",
            "tolerance (µm TIR)",
            "verdict",
            "most loaded tooth",
            "max chip (µm)",
            "compensated f_z (mm)",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    });
    let subtitle = format!(
        "{} report{} · units: lengths mm, runout µm, forces N, angles deg",
        sections.len(),
        if sections.len() == 1 { "" } else { "s" }
    );
    Ok(Page {
        title,
        subtitle: &subtitle,
        generator: format!("runout {}", env!("CARGO_PKG_VERSION")),
        comparison,
        sections,
    }
    .render()?)
}

/// The page of one typed report (what `--html FILE` writes).
pub fn render<R: ToSection>(report: &R) -> Result<String> {
    let s = report.section()?;
    page(&s.title.clone(), &[s])
}

/// The row of the comparison table from a verdict (the report's offset and angle come from the
/// verdict basis: ρ at the verdict's height).
pub(crate) fn compare_row(v: &VerdictReport) -> Vec<Cell> {
    let b = &v.basis;
    vec![
        Cell::num("/verdict/basis/offset_um", b.offset_um, 2),
        Cell::opt("/verdict/basis/offset_um_se", b.offset_um_se, 2),
        Cell::opt("/verdict/basis/angle_deg", b.angle_deg, 1),
        Cell::num("/verdict/tir_um", v.tir_um, 2),
        Cell::num("/verdict/tolerance_tir_um", v.tolerance_tir_um, 1),
        Cell::text(v.status.to_uppercase()),
        v.most_loaded_tooth.map_or(Cell::text("–"), |t| {
            Cell::int("/verdict/most_loaded_tooth", t).tooth(t)
        }),
        Cell::opt("/verdict/max_chip_um", v.max_chip_um, 2),
        Cell::opt("/verdict/compensated_fz_mm", v.compensated_fz_mm, 4),
    ]
}

/// Sections from saved JSON reports (`runout report`): each is read by its `schema` field into
/// its typed report; `tolerance_tir_um` judges the verdicts again. `name` names each in messages.
pub fn sections_from_json(
    reports: &[(String, String)],
    tolerance_tir_um: Option<f64>,
) -> Result<Vec<Section>> {
    use crate::verdict::HasVerdict;
    fn typed<R: serde::de::DeserializeOwned>(name: &str, v: Value) -> Result<R> {
        serde_json::from_value(v)
            .with_context(|| format!("{name}: not a valid report of its schema"))
    }
    fn judged<R: HasVerdict + ToSection>(
        mut r: R,
        tol: Option<f64>,
        name: &str,
    ) -> Result<Section> {
        r.set_tolerance(tol)?;
        let mut s = r.section()?;
        s.source = format!("{} (saved report {name})", s.source);
        Ok(s)
    }
    let mut out = Vec::new();
    for (name, text) in reports {
        let v: Value = serde_json::from_str(text)
            .with_context(|| format!("{name}: not JSON (expected a saved runout report)"))?;
        let schema = v
            .get("schema")
            .and_then(Value::as_str)
            .with_context(|| {
                format!(
                    "{name}: no `schema` field (expected a report written by `runout … --json`)"
                )
            })?
            .to_string();
        use crate::{chip, displacement as d, grind, shank};
        let tol = tolerance_tir_um;
        let s = match schema.as_str() {
            // the previous versions differ in the SE keys' spelling (read by aliases) and have
            // no `answer` (read as empty)
            "runout.displacement.teeth/2" | "runout.displacement.teeth/1" => {
                judged(typed::<d::TeethReport>(name, v)?, tol, name)?
            }
            "runout.displacement.heights/2" | "runout.displacement.heights/1" => {
                judged(typed::<d::HeightsReport>(name, v)?, tol, name)?
            }
            "runout.displacement.signal/2" | "runout.displacement.signal/1" => {
                judged(typed::<d::SignalReport>(name, v)?, tol, name)?
            }
            "runout.shank.force/2" | "runout.shank.force/1" => {
                judged(typed::<shank::ForceReport>(name, v)?, tol, name)?
            }
            "runout.grind.compensate/2" | "runout.grind.compensate/1" => {
                typed::<grind::CompensateReport>(name, v)?.section()?
            }
            "runout.chip.compare/1" => typed::<chip::CompareReport>(name, v)?.section()?,
            "runout.identify.recording/3" | "runout.identify.recording/2" => {
                sections::saved_identify(&v, name, tol)?
            }
            other => bail!(
                "{name}: schema `{other}` has no HTML page (expected one of: {})",
                SCHEMAS.join(", ")
            ),
        };
        out.push(s);
    }
    Ok(out)
}

/// The schemas `runout report` renders.
pub const SCHEMAS: &[&str] = &[
    "runout.identify.recording/3",
    "runout.displacement.teeth/2",
    "runout.displacement.heights/2",
    "runout.displacement.signal/2",
    "runout.shank.force/2",
    "runout.grind.compensate/2",
    "runout.chip.compare/1",
];
