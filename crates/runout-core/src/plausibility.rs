//! Plausibility guards: checks of an identified result (or of the data behind it) against what
//! physics and published data allow, each returning a [`Finding`] in the user's words with what
//! to check. A finding of severity [`Severity::NotIdentified`] means the value must not be used:
//! reports mark the quantity as not identified and say why.
//!
//! The thresholds and their sources:
//!
//! - **Runout** (`runout_size`): runouts of end mills in holders are typically 2–20 µm and rarely
//!   above 50 µm (docs/methods.md §6.3); a runout above 5 % of the cutter radius or 0.2 mm is
//!   not a holder error but a wrong model (diameter, profile, depth) or wrong data. A runout above
//!   the feed per tooth is physically possible, but then a tooth loses contact every revolution,
//!   which the user should know (warning).
//! - **Cutting coefficients** (`coefficients`): the linear (mechanistic) tangential shear
//!   coefficient K_tc of metals lies in 200–8 000 N/mm² — specific cutting forces k_c1 of
//!   500–3 100 N/mm² at h = 1 mm for the ISO material groups P, M, K, N, S, H (Sandvik Coromant,
//!   "specific cutting force" tables), rising as h^−0.25 towards the thin chips of milling
//!   (Kienzle), with margin. The radial shear and both tangential and radial edge coefficients are
//!   positive (the tool pushes the chip away and rubs the surface); K_rc ≤ 1.5·K_tc; edge
//!   coefficients below 300 N/mm. Axial coefficients may be negative (published fits with helical
//!   cutters have both signs) but |K_ac| ≤ K_tc, |K_ae| ≤ 100 N/mm. A value is judged with its
//!   standard error: implausible only when the whole ±2·SE interval is outside the range.
//! - **Clipping** (`ClipDetector`): an amplifier or ADC at its range limit produces flat tops —
//!   runs of equal samples at the channel's extreme.
//! - **Same data twice** (`duplicates`): identical sample content under two names.
//! - **Sensor senses** (`sensor_senses`): two displacement sensors on one shank see the same
//!   deflection with the same sign (the shank bends as a whole); a negative correlation of their
//!   variations means one sensor's sense or axis is reversed.

use crate::coefficients::CuttingCoefficients;

/// How serious a finding is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// The value can be used, but the user should know.
    Warning,
    /// The value must not be used: report it as not identified.
    NotIdentified,
}

/// One plausibility finding.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    /// Stable machine-readable code (e.g. `runout_too_large`).
    pub code: &'static str,
    /// Which quantity it concerns (e.g. `runout`, `K_tc`, a channel or file name).
    pub subject: String,
    /// What is wrong, in words, with the numbers.
    pub message: String,
    /// What the user can check or do.
    pub hint: String,
    /// Severity.
    pub severity: Severity,
}

impl std::fmt::Display for Finding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.message, self.hint)
    }
}

/// Largest force magnitude (N) a force recording may hold: above it a sample is no measured
/// force but a corrupt cell (a digit run together, an exponent, a sentinel such as `1e308`).
/// Milling dynamometers measure up to tens of kN (Kistler 9255C: ±30 kN in x/y, −10…60 kN in z)
/// and an end mill breaks under a few kN; the largest industrial load cells reach tens of MN. A
/// bound of 1e9 N is far above all of them (no real recording is refused), and far below the
/// magnitudes whose spectra overflow (a sample above ≈ 1e154 N has an infinite square).
pub const MAX_PLAUSIBLE_FORCE_N: f64 = 1e9;

/// Largest plausible runout as a fraction of the cutter radius.
pub const MAX_RUNOUT_FRACTION_OF_RADIUS: f64 = 0.05;
/// Largest plausible runout (mm).
pub const MAX_RUNOUT_MM: f64 = 0.2;

/// Check an identified runout ρ (mm) against the cutter radius R (mm) and the feed per tooth
/// f_z (mm).
///
/// ```
/// use runout_core::plausibility::{runout_size, Severity};
/// assert!(runout_size(0.008, 5.0, 0.08).is_empty());
/// let f = runout_size(1.495, 5.0, 0.08);
/// assert_eq!(f[0].severity, Severity::NotIdentified);
/// ```
pub fn runout_size(rho_mm: f64, radius_mm: f64, fz_mm: f64) -> Vec<Finding> {
    let mut out = Vec::new();
    let limit = (MAX_RUNOUT_FRACTION_OF_RADIUS * radius_mm).min(MAX_RUNOUT_MM);
    if !rho_mm.is_finite() || rho_mm > limit {
        out.push(Finding {
            code: "runout_too_large",
            subject: "runout".into(),
            message: format!(
                "runout ρ = {:.1} µm is implausible for a cutter of radius {radius_mm} mm \
                 (holder runouts are 2–20 µm, rarely above 50; limit {:.0} µm)",
                rho_mm * 1e3,
                limit * 1e3
            ),
            hint: "check the cutter description (diameter, profile: a ball or bull-nose cutter \
                   described as flat gives such values), the axial depth and the axis mapping"
                .into(),
            severity: Severity::NotIdentified,
        });
    } else if fz_mm > 0.0 && rho_mm > fz_mm {
        out.push(Finding {
            code: "runout_exceeds_feed",
            subject: "runout".into(),
            message: format!(
                "runout ρ = {:.1} µm exceeds the feed per tooth f_z = {:.1} µm: the shortest \
                 tooth cuts little or nothing",
                rho_mm * 1e3,
                fz_mm * 1e3
            ),
            hint: "re-clamp the tool or use a holder with less runout; the per-tooth loads are \
                   very unequal at this feed"
                .into(),
            severity: Severity::Warning,
        });
    }
    out
}

/// Plausible range of each coefficient `[K_tc, K_rc, K_ac, K_te, K_re, K_ae]` given K_tc
/// (module docs). Returns (low, high) in N/mm² or N/mm.
fn coefficient_range(index: usize, ktc: f64) -> (f64, f64) {
    match index {
        0 => (200.0, 8000.0),
        1 => (0.0, 1.5 * ktc.max(200.0)),
        2 => (-ktc.abs().max(200.0), ktc.abs().max(200.0)),
        3 | 4 => (0.0, 300.0),
        _ => (-100.0, 100.0),
    }
}

/// Names and units of the six coefficients, in `to_array` order.
pub const COEFFICIENT_NAMES: [(&str, &str); 6] = [
    ("K_tc", "N/mm²"),
    ("K_rc", "N/mm²"),
    ("K_ac", "N/mm²"),
    ("K_te", "N/mm"),
    ("K_re", "N/mm"),
    ("K_ae", "N/mm"),
];

/// Check identified coefficients (with their standard errors, if known) against the ranges
/// published for metals (module docs). A coefficient is implausible when its whole
/// value ± 2·SE interval lies outside the range.
///
/// ```
/// use runout_core::CuttingCoefficients;
/// use runout_core::plausibility::coefficients;
/// let k = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
/// assert!(coefficients(&k, None).is_empty());
/// let bad = CuttingCoefficients::new([1889.2, 806.1, 291.0], [-20.0, 113.7, -3.1]).unwrap();
/// assert_eq!(coefficients(&bad, Some([1.0; 6]))[0].subject, "K_te");
/// ```
pub fn coefficients(k: &CuttingCoefficients, se: Option<[f64; 6]>) -> Vec<Finding> {
    let v = k.to_array();
    let se = se.unwrap_or([0.0; 6]);
    let mut out = Vec::new();
    for (i, (&value, &s)) in v.iter().zip(&se).enumerate() {
        let (lo, hi) = coefficient_range(i, k.ktc);
        let s = if s.is_finite() { s.abs() } else { 0.0 };
        let (name, unit) = COEFFICIENT_NAMES[i];
        if !value.is_finite() || value + 2.0 * s < lo || value - 2.0 * s > hi {
            let sign = if value < 0.0 && lo >= 0.0 {
                "negative, which no metal cutting gives"
            } else {
                "outside the range published for metals"
            };
            out.push(Finding {
                code: "coefficient_implausible",
                subject: name.into(),
                message: format!(
                    "{name} = {value:.1} ± {s:.1} {unit} is {sign} ({lo:.0} to {hi:.0} {unit})"
                ),
                hint: "check the cutter diameter, the depths of cut, the feed per tooth and the \
                       force units; with one feed only the edge and shear terms are not separable"
                    .into(),
                severity: Severity::NotIdentified,
            });
        }
    }
    out
}

/// One side (maximum or minimum) of a [`ClipDetector`].
#[derive(Debug, Clone, Copy, Default)]
struct Extreme {
    value: f64,
    /// Length of the current run of samples equal to `value`.
    run: usize,
    /// Completed-or-current runs of at least `MIN_RUN` samples at `value`, and their samples.
    flat_runs: usize,
    flat_samples: usize,
}

impl Extreme {
    /// Take sample `v`; `beyond` tells whether v is a new extreme (above the max / below the min).
    #[inline]
    fn push(&mut self, v: f64, beyond: bool) {
        if beyond {
            // an earlier flat run was not at the limit after all
            *self = Extreme {
                value: v,
                run: 1,
                ..Default::default()
            };
        } else if v == self.value {
            self.run += 1;
            if self.run == ClipDetector::MIN_RUN {
                self.flat_runs += 1;
                self.flat_samples += ClipDetector::MIN_RUN;
            } else if self.run > ClipDetector::MIN_RUN {
                self.flat_samples += 1;
            }
        } else {
            self.run = 0;
        }
    }
}

/// Streaming detector of clipped channels. An amplifier or ADC at its range limit cuts every
/// peak that exceeds it, so the channel shows **several separate runs** of at least `MIN_RUN`
/// equal samples at its extreme. One run alone is not enough: a slowly varying quantised signal
/// (drift, an air cut) can sit on its largest code for a few samples once.
#[derive(Debug, Clone)]
pub struct ClipDetector {
    max: Extreme,
    min: Extreme,
    samples: usize,
}

impl Default for ClipDetector {
    fn default() -> Self {
        Self::new()
    }
}

impl ClipDetector {
    /// Consecutive equal samples at the extreme that make a flat top.
    pub const MIN_RUN: usize = 3;
    /// Separate flat tops needed to call the channel clipped.
    pub const MIN_RUNS: usize = 3;

    /// A detector that has seen nothing.
    pub fn new() -> Self {
        ClipDetector {
            max: Extreme {
                value: f64::NEG_INFINITY,
                ..Default::default()
            },
            min: Extreme {
                value: f64::INFINITY,
                ..Default::default()
            },
            samples: 0,
        }
    }

    /// Feed samples (non-finite ones are ignored).
    ///
    /// Blocks of 64 samples strictly inside (min, max) — almost all of a recording once its
    /// extremes have been seen — only end both runs: that is checked with one vectorised pass
    /// and applied at once; other blocks go sample by sample (issue 18: the detector was ≈ 2 %
    /// of a 100 MB `identify`).
    pub fn push(&mut self, values: &[f64]) {
        for block in values.chunks(64) {
            let (hi, lo) = (self.max.value, self.min.value);
            // NaN and ±∞ are never strictly inside, so such a block goes sample by sample
            let inside = block.iter().fold(true, |ok, &v| ok & (v < hi) & (v > lo));
            if inside {
                self.samples += block.len();
                self.max.run = 0;
                self.min.run = 0;
            } else {
                block.iter().for_each(|&v| self.push_one(v));
            }
        }
    }

    /// The largest magnitude among the finite samples fed so far (0 before any).
    ///
    /// ```
    /// use runout_core::plausibility::ClipDetector;
    /// let mut d = ClipDetector::new();
    /// assert_eq!(d.max_abs(), 0.0);
    /// d.push(&[1.0, -7.5, f64::NAN, 3.0]);
    /// assert_eq!(d.max_abs(), 7.5);
    /// ```
    pub fn max_abs(&self) -> f64 {
        if self.samples == 0 {
            0.0
        } else {
            self.max.value.abs().max(self.min.value.abs())
        }
    }

    /// One sample (ignored unless finite).
    #[inline]
    fn push_one(&mut self, v: f64) {
        if !v.is_finite() {
            return;
        }
        self.samples += 1;
        let above = v > self.max.value;
        self.max.push(v, above);
        let below = v < self.min.value;
        self.min.push(v, below);
    }

    /// The finding for channel `name` (unit `unit`), if it clipped.
    ///
    /// ```
    /// use runout_core::plausibility::ClipDetector;
    /// let sine: Vec<f64> = (0..5000).map(|q| 100.0 * (q as f64 * 0.05).sin()).collect();
    /// let mut ok = ClipDetector::new();
    /// ok.push(&sine);
    /// assert!(ok.finding("Fx", "N").is_none());
    /// let clipped: Vec<f64> = sine.iter().map(|v| v.clamp(-80.0, 80.0)).collect();
    /// let mut bad = ClipDetector::new();
    /// bad.push(&clipped);
    /// assert!(bad.finding("Fx", "N").is_some());
    /// ```
    pub fn finding(&self, name: &str, unit: &str) -> Option<Finding> {
        let top = self.max.flat_runs >= Self::MIN_RUNS;
        let bottom = self.min.flat_runs >= Self::MIN_RUNS;
        if !(top || bottom) || self.max.value == self.min.value {
            return None;
        }
        let (flat, at) = match (top, bottom) {
            (true, true) => (
                self.max.flat_samples + self.min.flat_samples,
                format!("{} and {} {unit}", self.min.value, self.max.value),
            ),
            (true, false) => (self.max.flat_samples, format!("{} {unit}", self.max.value)),
            _ => (self.min.flat_samples, format!("{} {unit}", self.min.value)),
        };
        Some(Finding {
            code: "channel_clipped",
            subject: name.into(),
            message: format!(
                "channel {name} is clipped: {flat} of {} samples sit flat at its extreme {at}",
                self.samples
            ),
            hint: "the amplifier or data-acquisition range was exceeded: re-record with a larger \
                   range; peaks and fits from clipped data are too low"
                .into(),
            severity: Severity::NotIdentified,
        })
    }
}

/// Findings for recordings with identical sample content: `items` are (name, content hash) pairs,
/// the hash over the samples only (not the header or the name).
pub fn duplicates(items: &[(String, u64)]) -> Vec<Finding> {
    let mut out = Vec::new();
    for (j, (name, hash)) in items.iter().enumerate() {
        if let Some((first, _)) = items[..j].iter().find(|(_, h)| h == hash) {
            out.push(Finding {
                code: "same_data_twice",
                subject: name.clone(),
                message: format!("{name} holds the same samples as {first}"),
                hint: "the same recording was passed twice (perhaps under another name): each \
                       feed needs its own recording"
                    .into(),
                severity: Severity::NotIdentified,
            });
        }
    }
    out
}

/// Check that two displacement sensors on one shank see the same deflection with the same sign:
/// the correlation coefficient of their mean-removed signals must be positive. `a` and `b` are
/// simultaneous samples of the same axis (sensor I and sensor II); `axis` names it.
///
/// ```
/// use runout_core::plausibility::sensor_senses;
/// let a: Vec<f64> = (0..400).map(|q| (q as f64 * 0.1).sin()).collect();
/// let b: Vec<f64> = a.iter().map(|v| 0.4 * v + 0.01).collect();
/// assert!(sensor_senses(&a, &b, "x").is_none());
/// let flipped: Vec<f64> = b.iter().map(|v| -v).collect();
/// assert!(sensor_senses(&a, &flipped, "x").is_some());
/// ```
pub fn sensor_senses(a: &[f64], b: &[f64], axis: &str) -> Option<Finding> {
    let n = a.len().min(b.len());
    if n < 3 {
        return None;
    }
    let ma = a[..n].iter().sum::<f64>() / n as f64;
    let mb = b[..n].iter().sum::<f64>() / n as f64;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a[..n].iter().zip(&b[..n]) {
        let (dx, dy) = (x - ma, y - mb);
        sab += dx * dy;
        saa += dx * dx;
        sbb += dy * dy;
    }
    if saa <= 0.0 || sbb <= 0.0 {
        return None;
    }
    let r = sab / (saa * sbb).sqrt();
    (r < -0.2).then(|| Finding {
        code: "sensor_senses_disagree",
        subject: axis.into(),
        message: format!(
            "the two shank sensors' {axis} signals move in opposite senses (correlation {r:.2}): \
             a bending shank moves both the same way"
        ),
        hint: format!(
            "check the sign of sensor II's {axis} channel in the axis mapping (e.g. `-{axis}`) \
             or the sensors' mounting"
        ),
        severity: Severity::NotIdentified,
    })
}

/// The most serious severity among `findings` (None when empty).
pub fn worst(findings: &[Finding]) -> Option<Severity> {
    findings.iter().map(|f| f.severity).max()
}

/// Ratio K_rc/K_tc assumed by [`force_magnitude`]: the middle of the 0.3–0.7 typical of metals
/// (the result depends on it only through √(1 + r²): ±8 % over that range).
pub const FORCE_MAGNITUDE_RADIAL_RATIO: f64 = 0.5;

/// Edge coefficients (K_te, K_re) in N/mm that [`force_magnitude`] allows a single recording's
/// mean force to contain: the upper end of published fits for steels, titanium and aluminium
/// alloys (K_te 15–40, K_re 25–70 N/mm; Altintas, *Manufacturing Automation*, 2nd ed., §2.4;
/// Budak, Altintas & Armarego 1996), with margin.
pub const FORCE_MAGNITUDE_EDGE_N_PER_MM: (f64, f64) = (50.0, 80.0);

/// Axial disks over which [`MeanForceGeometry::new`] integrates a shaped cutter (a cylinder
/// needs one: every disk has the same immersion).
const MEAN_FORCE_DISKS: usize = 64;

/// How the mean force of one revolution scales with the cut (docs/methods.md §0; Altintas,
/// *Manufacturing Automation*, eq. 2.17): summed over axial disks dz at height z above the tip,
/// with the immersion window [φ_st(z), φ_ex(z)] of the local radius R(z) ([`Cut::immersion_at`]),
///
/// F̄_x = K/(2π)·Σ dz·[−K_tc·f_z·(I_sc + r·I_ss) − K_te·I_c − K_re·I_s],
/// F̄_y = K/(2π)·Σ dz·[ K_tc·f_z·(I_ss − r·I_sc) + K_te·I_s − K_re·I_c]
///
/// with I_sc = ∫sin φ cos φ, I_ss = ∫sin²φ, I_c = ∫cos φ, I_s = ∫sin φ over the window
/// ([`crate::identify::immersion_integrals`]) and r = K_rc/K_tc. `shear` is the first bracket
/// per unit K_tc·f_z (mm: N per N/mm² per mm of feed), `edge` the second for the
/// coefficients [`FORCE_MAGNITUDE_EDGE_N_PER_MM`] (N). On a cylinder this is the closed form
/// K·a_p·f_z/(8π)·K_tc·√(1 + r²)·√(A² + B²), A = [cos 2φ], B = [2φ − sin 2φ].
///
/// [`Cut::immersion_at`]: crate::Cut::immersion_at
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanForceGeometry {
    /// Mean (F̄_x, F̄_y) per unit K_tc·f_z (mm).
    pub shear: [f64; 2],
    /// Mean (F̄_x, F̄_y) of the edge forces [`FORCE_MAGNITUDE_EDGE_N_PER_MM`] (N).
    pub edge: [f64; 2],
}

impl MeanForceGeometry {
    /// The geometry of `cut` with `cutter` (a_p from the tip; the cutter's radius profile
    /// sets each disk's immersion).
    ///
    /// ```
    /// use runout_core::{Cut, Cutter, MillingMode};
    /// use runout_core::plausibility::MeanForceGeometry;
    /// let cutter = Cutter::flat(10.0, 4, 30f64.to_radians()).unwrap();
    /// let cut = Cut::new(3240.0, 0.05, 2.0).unwrap().radial(2.0, MillingMode::Down, &cutter).unwrap();
    /// let g = MeanForceGeometry::new(&cutter, &cut);
    /// // K·a_p/(8π)·√1.25·√(A² + B²) for φ 126.9°–180° (A = 1.28, B = 0.8946): ≈ 0.55576 mm
    /// assert!((g.shear[0].hypot(g.shear[1]) - 0.55576).abs() < 1e-5);
    /// ```
    pub fn new(cutter: &crate::Cutter, cut: &crate::Cut) -> Self {
        let cylinder = matches!(cutter.profile(), crate::RadiusProfile::Flat);
        let n = if cylinder { 1 } else { MEAN_FORCE_DISKS };
        let ap = cut.ap();
        let dz = ap / n as f64;
        let k = cutter.teeth() as f64 / (2.0 * std::f64::consts::PI);
        let r = FORCE_MAGNITUDE_RADIAL_RATIO;
        let (kte, kre) = FORCE_MAGNITUDE_EDGE_N_PER_MM;
        let (mut shear, mut edge) = ([0.0; 2], [0.0; 2]);
        for d in 0..n {
            let z = (d as f64 + 0.5) * dz;
            let (st, ex) = cut.immersion_at(cutter, z.min(ap));
            let [isc, iss, ic, is, _] = crate::identify::immersion_integrals(st, ex);
            shear[0] += k * dz * (-isc - r * iss);
            shear[1] += k * dz * (iss - r * isc);
            edge[0] += k * dz * (-kte * ic - kre * is);
            edge[1] += k * dz * (kte * is - kre * ic);
        }
        MeanForceGeometry { shear, edge }
    }
}

/// One recording's mean force for [`force_magnitude`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanForce {
    /// Feed per tooth f_z (mm).
    pub fz_mm: f64,
    /// Mean (F_x, F_y) over the cut (N).
    pub fxy_n: [f64; 2],
}

/// The forces' magnitude against the cut's description (issue 21: a wrong `--diameter-mm`,
/// profile, teeth or force scale): the K_tc that the measured mean forces imply through
/// [`MeanForceGeometry`], against the 200–8 000 N/mm² published for metals (module docs).
///
/// * Recordings of one geometry at ≥ 2 feeds: the least-squares change of the mean force
///   vector with f_z, s = Σ(f_z − f̄_z)(F̄ − F̄̄)/Σ(f_z − f̄_z)², gives K_tc = |s|/|shear| free
///   of the edge forces (they do not depend on f_z).
/// * One feed: edge forces add to the mean, so the implied K_tc lies between
///   (|F̄| − |edge|)/(|shear|·f_z) and |F̄|/(|shear|·f_z); only a range entirely outside the
///   published one is reported.
///
/// `subject` names the recordings, `cut` describes the cut in words for the message. A finding
/// is a warning (the description of the cut contradicts the forces).
///
/// ```
/// use runout_core::{Cut, Cutter, MillingMode};
/// use runout_core::plausibility::{force_magnitude, MeanForce, MeanForceGeometry};
/// let cutter = Cutter::flat(10.0, 4, 30f64.to_radians()).unwrap();
/// let cut = Cut::new(3240.0, 0.05, 2.0).unwrap().radial(2.0, MillingMode::Down, &cutter).unwrap();
/// let g = MeanForceGeometry::new(&cutter, &cut);
/// // K_tc 2 000 N/mm² at f_z 0.05 and 0.08 mm plus an edge force: plausible
/// let f = |fz: f64| MeanForce { fz_mm: fz, fxy_n: [2000.0 * fz * g.shear[0] + 30.0,
///                                                  2000.0 * fz * g.shear[1] - 60.0] };
/// assert!(force_magnitude("a", "", &g, &[f(0.05), f(0.08)]).is_none());
/// // the same forces told a 100 mm cutter: K_tc ≈ 20 000 N/mm²
/// let big = Cutter::flat(100.0, 4, 30f64.to_radians()).unwrap();
/// let g100 = MeanForceGeometry::new(&big, &cut);
/// assert!(force_magnitude("a", "", &g100, &[f(0.05), f(0.08)]).is_some());
/// ```
pub fn force_magnitude(
    subject: &str,
    cut: &str,
    geometry: &MeanForceGeometry,
    forces: &[MeanForce],
) -> Option<Finding> {
    let shear = geometry.shear[0].hypot(geometry.shear[1]);
    let ok = |m: &MeanForce| m.fz_mm > 0.0 && m.fxy_n.iter().all(|v| v.is_finite());
    let forces: Vec<MeanForce> = forces.iter().copied().filter(ok).collect();
    if shear.is_nan() || shear <= 0.0 || forces.is_empty() {
        return None;
    }
    let n = forces.len() as f64;
    let fbar = forces.iter().map(|m| m.fz_mm).sum::<f64>() / n;
    let sxx: f64 = forces.iter().map(|m| (m.fz_mm - fbar).powi(2)).sum();
    let (lo, hi) = coefficient_range(0, 0.0);
    let (low, high, how) = if forces.len() >= 2 && sxx > (1e-3 * fbar).powi(2) * n {
        let mean = |i: usize| forces.iter().map(|m| m.fxy_n[i]).sum::<f64>() / n;
        let (mx, my) = (mean(0), mean(1));
        let sx: f64 = forces
            .iter()
            .map(|m| (m.fz_mm - fbar) * (m.fxy_n[0] - mx))
            .sum();
        let sy: f64 = forces
            .iter()
            .map(|m| (m.fz_mm - fbar) * (m.fxy_n[1] - my))
            .sum();
        let k = (sx / sxx).hypot(sy / sxx) / shear;
        let (f0, f1) = forces.iter().fold((f64::INFINITY, 0.0f64), |(a, b), m| {
            (a.min(m.fz_mm), b.max(m.fz_mm))
        });
        let how = format!(
            "the change of the mean force |F̄_xy| with f_z from {} to {} mm (free of edge forces)",
            g(f0),
            g(f1)
        );
        (k, k, how)
    } else {
        let m = forces
            .iter()
            .map(|m| m.fxy_n[0].hypot(m.fxy_n[1]))
            .sum::<f64>()
            / n;
        let edge = geometry.edge[0].hypot(geometry.edge[1]);
        let per = shear * fbar;
        let how = format!(
            "the mean force |F̄_xy| = {m:.1} N at f_z {} mm (of which edge forces may be up to \
             {edge:.1} N)",
            g(fbar)
        );
        ((m - edge).max(0.0) / per, m / per, how)
    };
    if high < lo {
        return Some(magnitude_finding(subject, cut, high, &how, (lo, hi)));
    }
    if low > hi {
        return Some(magnitude_finding(subject, cut, low, &how, (lo, hi)));
    }
    None
}

/// A number as a user wrote it: plain in the usual range, else with an exponent.
fn g(v: f64) -> String {
    if (1e-4..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

fn magnitude_finding(subject: &str, cut: &str, ktc: f64, how: &str, range: (f64, f64)) -> Finding {
    let implied = if ktc.is_finite() && ktc < 1e9 {
        format!("K_tc ≈ {ktc:.0} N/mm²")
    } else if ktc.is_finite() {
        format!("K_tc ≈ {ktc:.1e} N/mm²")
    } else {
        // a force over a vanishing f_z: no number to print (and never `inf` in a report)
        "K_tc beyond 1e308 N/mm²".to_string()
    };
    Finding {
        code: "force_magnitude_contradicts_cut",
        subject: subject.into(),
        message: format!(
            "in {subject} {how} implies a specific cutting force {implied} for {cut}; metals \
             lie in {:.0}–{:.0} N/mm²",
            range.0, range.1
        ),
        hint: "check --diameter-mm, --profile and a_e (they set the immersion), --teeth, a_p \
               and f_z, and the force channels' scale (N per volt, N or kN)"
            .into(),
        severity: Severity::Warning,
    }
}

#[cfg(test)]
mod clip_tests {
    use super::ClipDetector;
    use proptest::prelude::*;

    /// The detector's whole state, for comparing two of them.
    fn state(d: &ClipDetector) -> [f64; 9] {
        let e = |x: &super::Extreme| {
            [
                x.value,
                x.run as f64,
                x.flat_runs as f64,
                x.flat_samples as f64,
            ]
        };
        let [a, b, c, e4] = e(&d.max);
        let [f, g, h, i] = e(&d.min);
        [a, b, c, e4, f, g, h, i, d.samples as f64]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(500))]

        /// Blocks and sample by sample leave the same state, over quantised signals that clip
        /// (plateaus at both rails), drift to new extremes, and carry NaN or ±∞, pushed in
        /// slices of any length.
        #[test]
        fn blocks_equal_sample_by_sample(
            // mostly well inside the rails (so whole blocks are), now and then at or past them
            codes in prop::collection::vec(prop_oneof![40 => -2i32..=2, 1 => -6i32..=6], 0..700),
            rail in 1i32..6,
            specials in prop::collection::vec((0usize..700, 0u8..3), 0..4),
            cut in 1usize..200,
        ) {
            let mut v: Vec<f64> = codes.iter().map(|&c| f64::from(c.clamp(-rail, rail))).collect();
            for (at, k) in specials {
                if at < v.len() {
                    v[at] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][k as usize];
                }
            }
            let mut blocks = ClipDetector::new();
            v.chunks(cut).for_each(|c| blocks.push(c));
            let mut one = ClipDetector::new();
            v.iter().for_each(|&x| one.push_one(x));
            let (a, b) = (state(&blocks), state(&one));
            prop_assert!(a.iter().zip(&b).all(|(x, y)| x == y || (x.is_nan() && y.is_nan())), "{:?} vs {:?}", a, b);
            prop_assert_eq!(blocks.finding("Fx", "N"), one.finding("Fx", "N"));
        }
    }
}
