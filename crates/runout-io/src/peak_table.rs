//! Tables of per-tooth peak tests (seed 003 Table 1 style) for `runout identify tests`, as CSV
//! (comma, semicolon or tab; `#` comment lines) or TOML.
//!
//! CSV columns (header names, units in the names): `test` (label, optional), `fz_mm`, `ap_mm`,
//! `peak0_N` … `peak{K−1}_N` (teeth in cutting order, `conventions.md`), optionally
//! `se0_N` … (per-tooth standard errors), `fx_at_peak_N`, `fy_at_peak_N` (nominal forces at the
//! peak angle, **workpiece frame**, for seed eq. 17), and per-test overrides `diameter_mm`,
//! `ae_mm`, `mode`. Empty optional cells mean "not given".
//!
//! TOML: top-level `teeth`, `diameter_mm`, `ae_mm`, `mode`, `peak_immersion_deg` (all optional),
//! then `[[test]]` tables with `label`, `fz_mm`, `ap_mm`, `peaks_N = [..]`, optional `peaks_se_N`,
//! `fx_at_peak_N`, `fy_at_peak_N`, `diameter_mm`, `ae_mm`, `mode`.

use serde::Deserialize;
use std::path::Path;

/// Error naming the file, line (and column) and what was expected (the shared
/// [`crate::LocatedError`]).
pub type PeakTableError = crate::LocatedError;

/// Settings shared by all tests of a table (each may be overridden per test or by flags).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSettings {
    /// Number of teeth K (checked against the number of peaks).
    pub teeth: Option<usize>,
    /// Cutter diameter (mm).
    pub diameter_mm: Option<f64>,
    /// Radial depth a_e (mm).
    pub ae_mm: Option<f64>,
    /// Milling mode: up | down | slot.
    pub mode: Option<String>,
    /// Peak immersion angle γ (deg), overriding the one derived from the engagement.
    pub peak_immersion_deg: Option<f64>,
}

/// One test (row).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakRow {
    /// Label (defaults to the 1-based row number).
    #[serde(default)]
    pub label: String,
    /// Feed per tooth (mm).
    pub fz_mm: f64,
    /// Axial depth (mm).
    pub ap_mm: f64,
    /// Per-tooth peaks (N), teeth in cutting order.
    #[serde(rename = "peaks_N")]
    pub peaks_n: Vec<f64>,
    /// Per-tooth standard errors (N).
    #[serde(rename = "peaks_se_N", default)]
    pub peaks_se_n: Option<Vec<f64>>,
    /// Nominal F_x at the peak angle (N, workpiece frame).
    #[serde(rename = "fx_at_peak_N", default)]
    pub fx_at_peak_n: Option<f64>,
    /// Nominal F_y at the peak angle (N, workpiece frame).
    #[serde(rename = "fy_at_peak_N", default)]
    pub fy_at_peak_n: Option<f64>,
    /// Per-test diameter override (mm).
    #[serde(default)]
    pub diameter_mm: Option<f64>,
    /// Per-test a_e override (mm).
    #[serde(default)]
    pub ae_mm: Option<f64>,
    /// Per-test mode override.
    #[serde(default)]
    pub mode: Option<String>,
    /// Line in the file (for messages).
    #[serde(skip)]
    pub line: usize,
}

/// A table of tests.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PeakTable {
    /// Shared settings.
    pub settings: TableSettings,
    /// The tests.
    pub rows: Vec<PeakRow>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlTable {
    #[serde(flatten)]
    settings: TableSettings,
    test: Vec<PeakRow>,
}

/// Read a peak table; the format follows the extension (`.toml`, else CSV/TSV).
pub fn read_peak_table(path: &Path) -> Result<PeakTable, PeakTableError> {
    let file = path.display().to_string();
    let text = crate::textfile::read_text(path)?;
    let is_toml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if is_toml {
        parse_toml(&file, &text)
    } else {
        parse_csv(&file, &text)
    }
}

/// Parse a TOML peak table.
pub fn parse_toml(file: &str, text: &str) -> Result<PeakTable, PeakTableError> {
    if let Ok(doc) = text.parse::<toml::Table>() {
        if let Some(key) = doc
            .iter()
            .find_map(|(k, v)| crate::config::non_finite_key(v, k))
        {
            return Err(PeakTableError {
                file: file.into(),
                line: 0,
                column: None,
                message: format!("key `{key}`: expected a finite number, got nan or inf"),
            });
        }
    }
    let t: TomlTable = toml::from_str(text).map_err(|e: toml::de::Error| {
        let mut line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].lines().count().max(1))
            .unwrap_or(0);
        // an unknown key inside a flattened table is reported at the table's start: find it
        if let Some(name) = e.message().split('`').nth(1) {
            if e.message().starts_with("unknown field") {
                if let Some(i) = text.lines().position(|l| {
                    l.trim_start()
                        .strip_prefix(name)
                        .is_some_and(|r| r.trim_start().starts_with('='))
                }) {
                    line = i + 1;
                }
            }
        }
        PeakTableError {
            file: file.into(),
            line,
            column: None,
            message: crate::config::clip_quoted(e.message()),
        }
    })?;
    let mut rows = t.test;
    // line numbers of the [[test]] headers
    let lines: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.trim_start().starts_with("[[test]]"))
        .map(|(i, _)| i + 1)
        .collect();
    for (i, r) in rows.iter_mut().enumerate() {
        r.line = lines.get(i).copied().unwrap_or(0);
        if r.label.is_empty() {
            r.label = format!("{}", i + 1);
        }
    }
    Ok(PeakTable {
        settings: t.settings,
        rows,
    })
}

/// Parse a CSV/TSV peak table (see module docs for the columns) with the shared table reader
/// (`runout_io::table`: separator from the header row, decimal commas with `;` or tab).
pub fn parse_csv(file: &str, text: &str) -> Result<PeakTable, PeakTableError> {
    let t = crate::table::parse_text(file, text, false)?;
    let hl = t.header_line;
    let need = |name: &str| {
        t.column(name).ok_or_else(|| {
            PeakTableError::new(
                file,
                hl,
                format!(
                    "no column `{name}` (columns: {})",
                    crate::textfile::quote(&t.headers.join(", "))
                ),
            )
        })
    };
    let c_fz = need("fz_mm")?;
    let c_ap = need("ap_mm")?;
    let peak_cols: Vec<_> = (0..)
        .map_while(|i| t.column(&format!("peak{i}_N")))
        .collect();
    if peak_cols.len() < 2 {
        return Err(PeakTableError::new(
            file,
            hl,
            "expected per-tooth peak columns `peak0_N`, `peak1_N`, … (at least 2)",
        ));
    }
    let se_cols: Vec<_> = (0..).map_while(|i| t.column(&format!("se{i}_N"))).collect();
    if !se_cols.is_empty() && se_cols.len() != peak_cols.len() {
        return Err(PeakTableError::new(
            file,
            hl,
            format!(
                "{} standard-error columns se*_N for {} peak columns",
                se_cols.len(),
                peak_cols.len()
            ),
        ));
    }
    let c_label = t.column("test").or_else(|| t.column("label"));
    let (c_fx, c_fy) = (t.column("fx_at_peak_N"), t.column("fy_at_peak_N"));
    let (c_d, c_ae, c_mode) = (t.column("diameter_mm"), t.column("ae_mm"), t.column("mode"));
    if t.rows.is_empty() {
        return Err(PeakTableError::new(
            file,
            0,
            "no test rows after the header",
        ));
    }
    let mut rows = Vec::with_capacity(t.rows.len());
    for r in 0..t.rows.len() {
        let text_opt = |c: &Option<crate::table::Column>| {
            c.as_ref()
                .map(|c| t.text(r, c))
                .filter(|s| !s.is_empty())
                .map(String::from)
        };
        let all = |cols: &[crate::table::Column]| -> Result<Vec<f64>, PeakTableError> {
            cols.iter().map(|c| t.number(r, c)).collect()
        };
        rows.push(PeakRow {
            label: text_opt(&c_label).unwrap_or_else(|| format!("{}", r + 1)),
            fz_mm: t.number(r, &c_fz)?,
            ap_mm: t.number(r, &c_ap)?,
            peaks_n: all(&peak_cols)?,
            peaks_se_n: if se_cols.is_empty() {
                None
            } else {
                Some(all(&se_cols)?)
            },
            fx_at_peak_n: t.optional(r, c_fx.as_ref())?,
            fy_at_peak_n: t.optional(r, c_fy.as_ref())?,
            diameter_mm: t.optional(r, c_d.as_ref())?,
            ae_mm: t.optional(r, c_ae.as_ref())?,
            mode: text_opt(&c_mode),
            line: t.rows[r].0,
        });
    }
    Ok(PeakTable {
        settings: TableSettings {
            teeth: Some(peak_cols.len()),
            ..TableSettings::default()
        },
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_with_comments_semicolons_and_errors() {
        let t = "# seed 003\ntest;fz_mm;ap_mm;peak0_N;peak1_N;peak2_N\n1;0,08;1;10;20;30\n";
        let p = parse_csv("a.csv", t).unwrap();
        assert_eq!(p.rows[0].fz_mm, 0.08);
        assert_eq!(p.rows[0].peaks_n, vec![10.0, 20.0, 30.0]);
        assert_eq!(p.settings.teeth, Some(3));
        let bad = "fz_mm,ap_mm,peak0_N,peak1_N\n0.1,1,12x,3\n";
        let e = parse_csv("b.csv", bad).unwrap_err();
        assert_eq!((e.line, e.column), (2, Some(3)), "{e}");
        assert!(
            e.to_string()
                .starts_with("b.csv:2:3: `12x` in column `peak0_N`"),
            "{e}"
        );
        let e = parse_csv("c.csv", "fz_mm,peak0_N,peak1_N\n0.1,1,2\n").unwrap_err();
        assert!(e.to_string().contains("no column `ap_mm`"), "{e}");
        let e = parse_csv("d.csv", "fz_mm,ap_mm,peak0_N,peak1_N\n0.1,1,2\n").unwrap_err();
        assert!(e.to_string().starts_with("d.csv:2"), "{e}");
    }

    #[test]
    fn toml_table_and_unknown_key() {
        let t = "teeth = 2\nmode = \"up\"\n[[test]]\nfz_mm = 0.1\nap_mm = 1\npeaks_N = [1, 2]\n";
        let p = parse_toml("a.toml", t).unwrap();
        assert_eq!(p.rows[0].line, 3);
        assert_eq!(p.rows[0].label, "1");
        let e = parse_toml(
            "a.toml",
            "[[test]]\nfz_mm = 0.1\nap = 1\npeaks_N = [1, 2]\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("ap"), "{e}");
    }
}
