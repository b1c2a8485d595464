//! Cutting conditions: spindle speed, feed per tooth, depths and engagement.
//!
//! Immersion angle φ (`conventions.md`): clockwise from +y in the workpiece frame (Altintas).
//! Up-milling φ_st = 0, φ_ex = arccos(1 − a_e/R); down-milling φ_st = π − arccos(1 − a_e/R), φ_ex = π;
//! slotting 0 to π.

use crate::cutter::Cutter;
use crate::error::{positive, ParamError};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Milling mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MillingMode {
    /// Up (conventional) milling: entry at φ = 0.
    Up,
    /// Down (climb) milling: exit at φ = π.
    Down,
    /// Full slot: 0 to π.
    Slot,
}

impl std::str::FromStr for MillingMode {
    type Err = ParamError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "up" => Ok(MillingMode::Up),
            "down" => Ok(MillingMode::Down),
            "slot" => Ok(MillingMode::Slot),
            _ => Err(ParamError::new("mode", "one of up, down, slot", s)),
        }
    }
}

/// How the tool engages the workpiece.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Engagement {
    /// Radial depth a_e (mm) with a milling mode (a_e is ignored for `Slot`, which uses a_e = D).
    Radial {
        /// Radial depth of cut a_e (mm).
        ae: f64,
        /// Up, down or slot.
        mode: MillingMode,
    },
    /// Explicit entry and exit immersion angles (rad), 0 ≤ φ_st < φ_ex ≤ 2π... within one turn.
    Angles {
        /// Entry angle φ_st (rad).
        entry: f64,
        /// Exit angle φ_ex (rad).
        exit: f64,
    },
}

/// Steady 3-axis straight-feed cutting conditions.
///
/// ```
/// use runout_core::{Cut, Cutter, MillingMode};
/// let cutter = Cutter::flat(10.0, 4, 0.0).unwrap();
/// let cut = Cut::new(3240.0, 0.08, 1.0).unwrap().radial(2.0, MillingMode::Down, &cutter).unwrap();
/// let (st, ex) = cut.immersion(&cutter);
/// assert!((st.to_degrees() - 126.8699).abs() < 1e-4 && (ex.to_degrees() - 180.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cut {
    rpm: f64,
    fz: f64,
    ap: f64,
    engagement: Engagement,
}

impl Cut {
    /// Spindle speed (rpm), feed per tooth f_z (mm) and axial depth a_p (mm); slotting until
    /// [`Cut::radial`] or [`Cut::angles`] says otherwise.
    pub fn new(rpm: f64, fz_mm: f64, ap_mm: f64) -> Result<Self, ParamError> {
        use crate::limits::{
            positive_at_most, within, MAX_DEPTH_MM, MAX_FZ_MM, MAX_RPM, MIN_DEPTH_MM,
        };
        positive_at_most("rpm", rpm, MAX_RPM, "rpm")?;
        positive_at_most("fz_mm", fz_mm, MAX_FZ_MM, "mm")?;
        within("ap_mm", ap_mm, MIN_DEPTH_MM, MAX_DEPTH_MM, "mm")?;
        Ok(Cut {
            rpm,
            fz: fz_mm,
            ap: ap_mm,
            engagement: Engagement::Radial {
                ae: f64::NAN,
                mode: MillingMode::Slot,
            },
        })
    }

    /// Set the radial engagement a_e (mm) and mode; checks 0 < a_e ≤ D.
    pub fn radial(
        mut self,
        ae_mm: f64,
        mode: MillingMode,
        cutter: &Cutter,
    ) -> Result<Self, ParamError> {
        let ae = if mode == MillingMode::Slot {
            cutter.diameter()
        } else {
            positive("ae_mm", ae_mm)?
        };
        if ae > cutter.diameter() * (1.0 + 1e-12) {
            return Err(ParamError::new(
                "ae_mm",
                format!("a radial depth 0 < a_e <= D = {} mm", cutter.diameter()),
                ae_mm,
            ));
        }
        self.engagement = Engagement::Radial {
            ae: ae.min(cutter.diameter()),
            mode,
        };
        Ok(self)
    }

    /// Set explicit entry/exit immersion angles (rad), 0 ≤ entry < exit ≤ entry + 2π.
    pub fn angles(mut self, entry_rad: f64, exit_rad: f64) -> Result<Self, ParamError> {
        if !(entry_rad.is_finite() && exit_rad.is_finite()) {
            return Err(ParamError::new(
                "entry_deg/exit_deg",
                "finite angles",
                format!("{entry_rad}, {exit_rad}"),
            ));
        }
        if !(exit_rad > entry_rad && exit_rad - entry_rad <= 2.0 * PI + 1e-12) {
            return Err(ParamError::new(
                "exit_deg",
                "an exit angle after the entry angle, at most 360° later",
                format!(
                    "entry {:.4}°, exit {:.4}°",
                    entry_rad.to_degrees(),
                    exit_rad.to_degrees()
                ),
            ));
        }
        self.engagement = Engagement::Angles {
            entry: entry_rad,
            exit: exit_rad,
        };
        Ok(self)
    }

    /// Spindle speed (rpm).
    pub fn rpm(&self) -> f64 {
        self.rpm
    }
    /// Spindle angular speed ω (rad/s).
    pub fn omega(&self) -> f64 {
        self.rpm * 2.0 * PI / 60.0
    }
    /// Spindle period T (s).
    pub fn period(&self) -> f64 {
        60.0 / self.rpm
    }
    /// Feed per tooth f_z (mm).
    pub fn fz(&self) -> f64 {
        self.fz
    }
    /// Axial depth a_p (mm).
    pub fn ap(&self) -> f64 {
        self.ap
    }
    /// Engagement.
    pub fn engagement(&self) -> Engagement {
        self.engagement
    }
    /// Feed rate (mm/min) for a cutter with `teeth` teeth.
    pub fn feed_mm_per_min(&self, teeth: usize) -> f64 {
        self.fz * teeth as f64 * self.rpm
    }

    /// Entry and exit immersion angles (φ_st, φ_ex) in rad (`conventions.md`).
    pub fn immersion(&self, cutter: &Cutter) -> (f64, f64) {
        match self.engagement {
            Engagement::Angles { entry, exit } => (entry, exit),
            Engagement::Radial { ae, mode } => {
                let r = cutter.radius();
                let a = (1.0 - ae / r).clamp(-1.0, 1.0).acos();
                match mode {
                    MillingMode::Up => (0.0, a),
                    MillingMode::Down => (PI - a, PI),
                    MillingMode::Slot => (0.0, PI),
                }
            }
        }
    }

    /// Entry and exit immersion angles (rad) of the disk at height `z` above the tip, with a_e
    /// measured from the wall at that height ([`crate::edge`]): the wall of the previous pass is
    /// at R(z) − a_e, so the window is arccos(1 − a_e/R(z)) wide (clamped: a full slot [0, π]
    /// where a_e ≥ 2R(z)). Equals [`Cut::immersion`] on a cylinder.
    pub fn immersion_at(&self, cutter: &Cutter, z: f64) -> (f64, f64) {
        match self.engagement {
            Engagement::Angles { entry, exit } => (entry, exit),
            Engagement::Radial { ae, mode } => {
                let r = cutter.radius_at(z);
                let a = if r > 0.0 {
                    (1.0 - ae / r).clamp(-1.0, 1.0).acos()
                } else {
                    PI
                };
                match mode {
                    MillingMode::Up => (0.0, a),
                    MillingMode::Down => (PI - a, PI),
                    MillingMode::Slot => (0.0, PI),
                }
            }
        }
    }
}
