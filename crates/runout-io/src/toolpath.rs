//! Cutter-location (CL) toolpaths for 5-axis chip-thickness evaluation (methods.md §2.1).
//!
//! Two formats:
//! * **APT CL** (`.apt`, `.cl`, `.cls`, anything not `.csv`): `GOTO/x,y,z[,i,j,k]`, `FEDRAT/f[,MMPM|IPM]`
//!   (also `FEDRAT/MMPM,f`), `RAPID`, `MULTAX[/ON|/OFF]`, `UNITS/MM|INCHES`, `$$` comments,
//!   statements continued on the next line by a trailing `$`. Other statements (PARTNO, CUTTER,
//!   SPINDL, LOADTL, COOLNT, FINI, …) are ignored; `CIRCLE` is refused (linearise the path first).
//! * **CSV**: `x_mm,y_mm,z_mm,i,j,k[,feed_mm_min]`, optional header line, `#` comments.
//!
//! Tool tip points in mm, tool axis (tip → holder) as given; a zero axis is an error, a non-unit
//! axis is normalised and a warning is returned in [`Toolpath::warnings`] (never printed here).

use runout_core::chip::{ClPoint, Vec3};
use std::path::Path;

/// One CL point as read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolpathPoint {
    /// Tool tip position (mm).
    pub p: [f64; 3],
    /// Unit tool axis.
    pub axis: [f64; 3],
    /// Feed of the move that reaches this point (mm/min); `None` if none was set yet.
    pub feed_mm_min: Option<f64>,
    /// The move to this point is a rapid (not cutting).
    pub rapid: bool,
    /// 1-based line of the file where the statement starts.
    pub line: usize,
}

/// A toolpath read from a file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Toolpath {
    /// Points in file order.
    pub points: Vec<ToolpathPoint>,
    /// Non-fatal findings (normalised axes …), with line numbers.
    pub warnings: Vec<String>,
}

/// A toolpath error naming the file and line.
#[derive(Debug, thiserror::Error)]
pub enum ToolpathError {
    /// The file could not be read.
    #[error("{file}: cannot read: {}", crate::report::io_problem(.error))]
    Io {
        /// The file.
        file: String,
        /// The I/O error. (part of the message, not a `source()`: printed once)
        error: std::io::Error,
    },
    /// A malformed statement.
    #[error("{file}:{line}: {message}")]
    Parse {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The path as a whole is unusable.
    #[error("{file}: {message}")]
    Path {
        /// The file.
        file: String,
        /// What is wrong.
        message: String,
    },
}

/// Read a toolpath; CSV when the extension is `.csv`, APT CL otherwise.
pub fn read_toolpath(path: &Path) -> Result<Toolpath, ToolpathError> {
    let name = path.display().to_string();
    let text = crate::textfile::read_text(path).map_err(|e| match e.line() {
        Some(line) => ToolpathError::Parse {
            file: name.clone(),
            line,
            message: e.message,
        },
        None => ToolpathError::Path {
            file: name.clone(),
            message: e.message,
        },
    })?;
    let is_csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_csv {
        parse_cl_csv(&name, &text)
    } else {
        parse_apt(&name, &text)
    }
}

/// Normalise an axis read at `line`: error when zero, warning when not unit length.
fn unit_axis(
    file: &str,
    line: usize,
    v: [f64; 3],
    warnings: &mut Vec<String>,
) -> Result<[f64; 3], ToolpathError> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if !(n.is_finite() && n > 1e-12) {
        return Err(ToolpathError::Parse {
            file: file.into(),
            line,
            message: format!(
                "tool axis ({}, {}, {}) has zero length; expected a direction i,j,k",
                v[0], v[1], v[2]
            ),
        });
    }
    if (n - 1.0).abs() > 1e-6 {
        warnings.push(format!(
            "{file}:{line}: tool axis ({}, {}, {}) has length {n:.6}; normalised",
            v[0], v[1], v[2]
        ));
    }
    Ok([v[0] / n, v[1] / n, v[2] / n])
}

/// Tool tip coordinates within [`runout_core::limits::MAX_COORDINATE_MM`].
fn check_point(file: &str, line: usize, p: &[f64; 3]) -> Result<(), ToolpathError> {
    for (a, v) in ["x", "y", "z"].iter().zip(p) {
        runout_core::limits::coordinate(&format!("{a}_mm"), *v).map_err(|e| {
            ToolpathError::Parse {
                file: file.into(),
                line,
                message: format!("coordinate out of range: {e}"),
            }
        })?;
    }
    Ok(())
}

/// One logical APT statement with the line it starts on.
struct Statement {
    line: usize,
    text: String,
}

/// Join continuation lines (trailing `$`) and strip `$$` comments.
fn apt_statements(text: &str) -> Vec<Statement> {
    let mut out = Vec::new();
    let mut cur: Option<Statement> = None;
    for (idx, raw) in text.lines().enumerate() {
        let code = raw.split("$$").next().unwrap_or("").trim();
        let (body, cont) = match code.strip_suffix('$') {
            Some(b) => (b.trim_end(), true),
            None => (code, false),
        };
        match cur.as_mut() {
            Some(s) => s.text.push_str(body),
            None if !body.is_empty() || cont => {
                cur = Some(Statement {
                    line: idx + 1,
                    text: body.to_string(),
                })
            }
            None => {}
        }
        if !cont {
            if let Some(s) = cur.take() {
                if !s.text.trim().is_empty() {
                    out.push(s);
                }
            }
        }
    }
    if let Some(s) = cur {
        out.push(s);
    }
    out
}

/// APT statements that do not move the tool or set the feed: ignored without a warning.
const IGNORED_APT: &[&str] = &[
    "PARTNO",
    "CUTTER",
    "SPINDL",
    "LOADTL",
    "COOLNT",
    "FINI",
    "PPRINT",
    "INSERT",
    "REMARK",
    "TLAXIS",
    "INTOL",
    "OUTTOL",
    "TOLER",
    "CLRSRF",
    "END",
    "STOP",
    "OPSTOP",
    "SELCTL",
    "TLON",
    "TLOFF",
    "SET",
    "MACHIN",
    "PPFUN",
    "TITLE",
    "CUTCOM",
    "ORIGIN",
    "DELAY",
    "AUXFUN",
    "PREFUN",
    "CLEARP",
    "RETRCT",
    "SEQNO",
    "NOPOST",
    "TRANS",
    "OPERATION",
    "OPNAME",
    "TOOL",
    "PIVOTZ",
    "DISPLY",
    "LINTOL",
    "HEAD",
    "MODE",
    "THICK",
    "CYCLE",
    "DRAFT",
    "FROM",
    "END-OF-PATH",
    "TPRINT",
    "GOHOME",
    "MSYS",
    "RESET",
    "ROTABL",
    "ROTATE",
];

/// At most 80 characters of `text` for a message.
fn clip(text: &str) -> String {
    match text.char_indices().nth(80) {
        Some((i, _)) => format!("{}…", &text[..i]),
        None => text.to_string(),
    }
}

/// APT parser state.
struct Apt<'a> {
    file: &'a str,
    scale: f64,
    feed: Option<f64>,
    rapid: bool,
    multax: bool,
    path: Toolpath,
}

impl Apt<'_> {
    fn err(&self, line: usize, message: impl Into<String>) -> ToolpathError {
        ToolpathError::Parse {
            file: self.file.into(),
            line,
            message: message.into(),
        }
    }

    fn numbers(&self, line: usize, word: &str, args: &str) -> Result<Vec<f64>, ToolpathError> {
        args.split(',')
            .map(|t| {
                let t = t.trim();
                t.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        self.err(
                            line,
                            format!("{word}: `{}` is not a number", crate::textfile::quote(t)),
                        )
                    })
            })
            .collect()
    }

    fn statement(&mut self, st: &Statement) -> Result<(), ToolpathError> {
        let (word, args) = match st.text.split_once('/') {
            Some((w, a)) => (w.trim().to_ascii_uppercase(), a.trim()),
            None => (st.text.trim().to_ascii_uppercase(), ""),
        };
        match word.as_str() {
            "GOTO" => self.goto(st.line, args),
            "FEDRAT" => self.fedrat(st.line, args),
            "RAPID" => {
                self.rapid = true;
                Ok(())
            }
            "MULTAX" => {
                self.multax = !args.eq_ignore_ascii_case("OFF");
                Ok(())
            }
            "UNITS" => self.units(st.line, args),
            "CIRCLE" | "MOVARC" => Err(self.err(
                st.line,
                format!("{word}: circular moves are not supported; export linearised GOTO points"),
            )),
            w if IGNORED_APT.contains(&w) => Ok(()),
            w if !w.starts_with(|c: char| c.is_ascii_alphabetic())
                || !w
                    .chars()
                    .all(|c| c.is_ascii_alphabetic() || c == '_' || c == '-') =>
            {
                Err(self.err(
                    st.line,
                    format!(
                        "unknown APT record `{}` (not a word; expected GOTO, FEDRAT, RAPID, MULTAX, UNITS or another APT statement)",
                        clip(&st.text)
                    ),
                ))
            }
            w => {
                self.path.warnings.push(format!(
                    "{}:{}: unknown APT record `{}` ignored",
                    self.file,
                    st.line,
                    clip(w)
                ));
                Ok(())
            }
        }
    }

    fn units(&mut self, line: usize, args: &str) -> Result<(), ToolpathError> {
        self.scale = match args.to_ascii_uppercase().as_str() {
            "MM" => 1.0,
            "INCHES" | "INCH" => 25.4,
            other => return Err(self.err(line, format!("UNITS/{other}: expected MM or INCHES"))),
        };
        Ok(())
    }

    fn fedrat(&mut self, line: usize, args: &str) -> Result<(), ToolpathError> {
        let mut value = None;
        let mut per_min_scale = self.scale;
        for tok in args.split(',').map(str::trim) {
            match tok.to_ascii_uppercase().as_str() {
                "MMPM" => per_min_scale = 1.0,
                "IPM" => per_min_scale = 25.4,
                "MMPR" | "IPR" => {
                    return Err(self.err(
                        line,
                        format!("FEDRAT/{tok}: feed per revolution is not supported; give mm/min (MMPM) or IPM"),
                    ))
                }
                _ => {
                    let v: f64 = tok.parse().map_err(|_| {
                        self.err(line, format!("FEDRAT: `{}` is not a number or MMPM/IPM", crate::textfile::quote(tok)))
                    })?;
                    value = Some(v);
                }
            }
        }
        let v = value.ok_or_else(|| self.err(line, "FEDRAT: expected a feed value"))?;
        let v = runout_core::limits::feed_mm_min("FEDRAT", v * per_min_scale)
            .map_err(|e| self.err(line, e.to_string()))?;
        self.feed = Some(v);
        self.rapid = false;
        Ok(())
    }

    fn goto(&mut self, line: usize, args: &str) -> Result<(), ToolpathError> {
        let v = self.numbers(line, "GOTO", args)?;
        let axis = match v.len() {
            3 if !self.multax => [0.0, 0.0, 1.0],
            3 => {
                return Err(self.err(
                    line,
                    "GOTO: MULTAX is on, expected x,y,z,i,j,k (6 values), got 3",
                ))
            }
            6 => [v[3], v[4], v[5]],
            n => {
                return Err(self.err(
                    line,
                    format!("GOTO: expected x,y,z or x,y,z,i,j,k, got {n} values"),
                ))
            }
        };
        let axis = unit_axis(self.file, line, axis, &mut self.path.warnings)?;
        let p = [v[0] * self.scale, v[1] * self.scale, v[2] * self.scale];
        check_point(self.file, line, &p)?;
        self.path.points.push(ToolpathPoint {
            p,
            axis,
            feed_mm_min: self.feed,
            rapid: self.rapid,
            line,
        });
        self.rapid = false;
        Ok(())
    }
}

/// Parse APT CL text; `file` names the source in errors.
///
/// ```
/// let apt = "MULTAX\nFEDRAT/1200.0,MMPM\nGOTO/0,0,5,0,0,1 $$ start\nGOTO/10,0,5,$\n 0.0,0.6,0.8\n";
/// let p = runout_io::toolpath::parse_apt("demo.apt", apt).unwrap();
/// assert_eq!(p.points.len(), 2);
/// assert_eq!(p.points[1].line, 4);
/// assert!((p.points[1].axis[1] - 0.6).abs() < 1e-12);
/// ```
pub fn parse_apt(file: &str, text: &str) -> Result<Toolpath, ToolpathError> {
    let mut apt = Apt {
        file,
        scale: 1.0,
        feed: None,
        rapid: false,
        multax: false,
        path: Toolpath::default(),
    };
    for st in apt_statements(text) {
        apt.statement(&st)?;
    }
    if apt.path.points.is_empty() {
        return Err(ToolpathError::Path {
            file: file.into(),
            message: "no GOTO points".into(),
        });
    }
    Ok(apt.path)
}

/// One data row of a numeric toolpath CSV.
struct NumericRow {
    /// 1-based line number.
    line: usize,
    /// The required values (all columns of the header but the trailing feed), finite.
    values: Vec<f64>,
    /// The optional trailing feed (mm/min, > 0).
    feed_mm_min: Option<f64>,
}

/// Rows of a comma-separated numeric table whose last column (`feed_mm_min`) is optional:
/// `#` starts a comment, blank lines are skipped, a text first row must be `header` (case
/// insensitive, with or without the feed column). Errors name the file, line and field.
fn numeric_rows(file: &str, text: &str, header: &[&str]) -> Result<Vec<NumericRow>, ToolpathError> {
    let err = |line: usize, message: String| ToolpathError::Parse {
        file: file.into(),
        line,
        message,
    };
    let full = header.len();
    let counts = full - 1..=full;
    let mut rows: Vec<NumericRow> = Vec::new();
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        let body = raw.split('#').next().unwrap_or("").trim();
        if body.is_empty() {
            continue;
        }
        let fields: Vec<&str> = body.split(',').map(str::trim).collect();
        if rows.is_empty() && fields[0].parse::<f64>().is_err() {
            let ok = counts.contains(&fields.len())
                && fields
                    .iter()
                    .zip(header)
                    .all(|(f, h)| f.eq_ignore_ascii_case(h));
            if !ok {
                return Err(err(
                    line,
                    format!(
                        "header `{}`: expected {}",
                        crate::textfile::quote(body),
                        header.join(",")
                    ),
                ));
            }
            continue;
        }
        if !counts.contains(&fields.len()) {
            return Err(err(
                line,
                format!(
                    "expected {} or {full} fields ({}[,{}]), got {}",
                    full - 1,
                    header[..full - 1].join(","),
                    header[full - 1],
                    fields.len()
                ),
            ));
        }
        let mut values = fields
            .iter()
            .enumerate()
            .map(|(q, f)| {
                f.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        err(
                            line,
                            format!(
                                "field {} (`{}`) is not a number",
                                q + 1,
                                crate::textfile::quote(f)
                            ),
                        )
                    })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        let feed_mm_min = if values.len() == full {
            let f = values.pop().expect("full row");
            runout_core::limits::feed_mm_min("feed_mm_min", f)
                .map_err(|e| err(line, e.to_string()))?;
            Some(f)
        } else {
            None
        };
        rows.push(NumericRow {
            line,
            values,
            feed_mm_min,
        });
    }
    Ok(rows)
}

/// Parse CSV `x_mm,y_mm,z_mm,i,j,k[,feed_mm_min]`; an optional first header line is checked.
///
/// ```
/// let csv = "x_mm,y_mm,z_mm,i,j,k,feed_mm_min\n0,0,0,0,0,1,600\n5,0,0,0,0,2,600\n";
/// let p = runout_io::toolpath::parse_cl_csv("p.csv", csv).unwrap();
/// assert_eq!(p.points.len(), 2);
/// assert_eq!(p.warnings.len(), 1); // axis (0,0,2) normalised
/// ```
pub fn parse_cl_csv(file: &str, text: &str) -> Result<Toolpath, ToolpathError> {
    const HEADER: [&str; 7] = ["x_mm", "y_mm", "z_mm", "i", "j", "k", "feed_mm_min"];
    let mut path = Toolpath::default();
    for row in numeric_rows(file, text, &HEADER)? {
        let v = &row.values;
        let feed = row
            .feed_mm_min
            .or_else(|| path.points.last().and_then(|p| p.feed_mm_min));
        let axis = unit_axis(file, row.line, [v[3], v[4], v[5]], &mut path.warnings)?;
        check_point(file, row.line, &[v[0], v[1], v[2]])?;
        path.points.push(ToolpathPoint {
            p: [v[0], v[1], v[2]],
            axis,
            feed_mm_min: feed,
            rapid: false,
            line: row.line,
        });
    }
    if path.points.is_empty() {
        return Err(ToolpathError::Path {
            file: file.into(),
            message: "no points".into(),
        });
    }
    Ok(path)
}

impl Toolpath {
    /// CL points of the first cutting section for the kinematics (`runout_core::chip::ClPath`),
    /// feed in mm/s: it starts at the last rapid point before the first feed move and ends before
    /// the next rapid; `default_feed_mm_min` fills a missing feed.
    /// The feed of the move n → n+1 is the feed read with point n+1 (APT modal FEDRAT).
    /// Consecutive duplicate points are merged (with a warning).
    pub fn cl_points(
        &mut self,
        file: &str,
        default_feed_mm_min: Option<f64>,
    ) -> Result<Vec<ClPoint>, ToolpathError> {
        let mut out: Vec<ClPoint> = Vec::with_capacity(self.points.len());
        let mut lines: Vec<usize> = Vec::new();
        for (n, q) in self.points.iter().enumerate() {
            let next_feed = self.points.get(n + 1).and_then(|p| {
                if p.rapid {
                    None
                } else {
                    p.feed_mm_min.or(default_feed_mm_min)
                }
            });
            let p = Vec3::new(q.p[0], q.p[1], q.p[2]);
            let u = Vec3::new(q.axis[0], q.axis[1], q.axis[2]);
            if q.rapid {
                if out.len() >= 2 {
                    break; // a rapid ends the first cutting section
                }
                out.clear(); // approach: the section starts at the last rapid point
                lines.clear();
            } else if let Some(last) = out.last() {
                if (last.p - p).norm() < 1e-9 {
                    if (last.u - u).norm() > 1e-9 {
                        return Err(ToolpathError::Parse {
                            file: file.into(),
                            line: q.line,
                            message: "tool axis changes without a tip move; not supported".into(),
                        });
                    }
                    self.warnings
                        .push(format!("{file}:{}: duplicate point merged", q.line));
                    continue;
                }
            }
            out.push(ClPoint {
                p,
                u,
                feed: next_feed.unwrap_or(f64::NAN) / 60.0,
            });
            lines.push(q.line);
        }
        if out.len() < 2 {
            return Err(ToolpathError::Path {
                file: file.into(),
                message: "fewer than 2 feed points (rapids and points before the first FEDRAT are not cut)".into(),
            });
        }
        let last = out.len() - 1;
        out[last].feed = out[last - 1].feed;
        if let Some(n) = out[..last].iter().position(|c| !c.feed.is_finite()) {
            return Err(ToolpathError::Parse {
                file: file.into(),
                line: lines[n],
                message: "no feed for the move from this point: give FEDRAT / feed_mm_min or --feed-mm-min".into(),
            });
        }
        Ok(out)
    }
}

/// One block of a joint-space program (machine without RTCP, head-head A/C kinematics).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointBlock {
    /// Pivot position X, Y, Z (mm).
    pub xyz: [f64; 3],
    /// A axis (deg, about x).
    pub a_deg: f64,
    /// C axis (deg, about z).
    pub c_deg: f64,
    /// Feed (mm/min) of the move that reaches this block, if given (modal).
    pub feed_mm_min: Option<f64>,
    /// 1-based line.
    pub line: usize,
}

/// Parse CSV `x_mm,y_mm,z_mm,a_deg,c_deg[,feed_mm_min]` (optional header, `#` comments):
/// machine joints for [`runout_core::chip::JointPath`].
///
/// ```
/// let j = runout_io::toolpath::parse_joint_csv("j.csv", "x_mm,y_mm,z_mm,a_deg,c_deg,feed_mm_min\n0,0,150,0,0,600\n10,0,150,5,0\n").unwrap();
/// assert_eq!(j.len(), 2);
/// assert_eq!(j[1].feed_mm_min, Some(600.0));
/// ```
pub fn parse_joint_csv(file: &str, text: &str) -> Result<Vec<JointBlock>, ToolpathError> {
    const HEADER: [&str; 6] = ["x_mm", "y_mm", "z_mm", "a_deg", "c_deg", "feed_mm_min"];
    let mut out: Vec<JointBlock> = Vec::new();
    for row in numeric_rows(file, text, &HEADER)? {
        let v = &row.values;
        let feed = row
            .feed_mm_min
            .or_else(|| out.last().and_then(|b| b.feed_mm_min));
        check_point(file, row.line, &[v[0], v[1], v[2]])?;
        out.push(JointBlock {
            xyz: [v[0], v[1], v[2]],
            a_deg: v[3],
            c_deg: v[4],
            feed_mm_min: feed,
            line: row.line,
        });
    }
    if out.len() < 2 {
        return Err(ToolpathError::Path {
            file: file.into(),
            message: "fewer than 2 joint blocks".into(),
        });
    }
    Ok(out)
}

/// Joint blocks → [`runout_core::chip::JointPoint`] (rad, feed mm/s of the move to the next
/// block = the feed read with that next block; `default_feed_mm_min` fills a missing one).
pub fn joint_points(
    file: &str,
    blocks: &[JointBlock],
    default_feed_mm_min: Option<f64>,
) -> Result<Vec<runout_core::chip::JointPoint>, ToolpathError> {
    let mut out = Vec::with_capacity(blocks.len());
    for (n, b) in blocks.iter().enumerate() {
        let next = blocks.get(n + 1).or(blocks.get(n.saturating_sub(1)));
        let feed = next
            .and_then(|q| q.feed_mm_min)
            .or(default_feed_mm_min)
            .ok_or_else(|| ToolpathError::Parse {
                file: file.into(),
                line: b.line,
                message: "no feed for the move from this block: give feed_mm_min".into(),
            })?;
        out.push(runout_core::chip::JointPoint {
            xyz: Vec3::new(b.xyz[0], b.xyz[1], b.xyz[2]),
            a: b.a_deg.to_radians(),
            c: b.c_deg.to_radians(),
            feed: feed / 60.0,
        });
    }
    Ok(out)
}
