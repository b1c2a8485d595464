//! One per-disk edge geometry and engagement table for every force kernel (issue 12).
//!
//! Both [`crate::ForceModel::simulate`] and [`crate::identify::RevolutionModel`] consume an
//! [`EdgeTable`], through one shared kernel (`force::kernel`, issue 18): a change of the cutter
//! model (profile, lead angle, engagement) happens here and only here.
//!
//! Discretisation (Engin & Altintas 2001, "Mechanics and dynamics of general milling cutters,
//! Part I: helical end mills", Int. J. Mach. Tools Manuf. 41, §2–3; Lee & Altintas 1996,
//! "Prediction of ball-end milling forces from orthogonal cutting data", IJMTM 36): the flutes are
//! cut into `disks` axial slices of height dz = a_p/disks at mid-heights z_j = (j + ½)·dz
//! measured from the tip. Per disk:
//!
//! * R(z_j) — the envelope radius ([`Cutter::radius_at`]);
//! * κ(z_j) — the axial immersion (lead) angle ([`Cutter::lead_angle`]); the uncut chip
//!   thickness normal to the edge is h·sin κ and the chip width (edge length of the disk,
//!   E&A's db) is db = dz / sin κ, so the shear force K_c·(h sin κ)·(dz/sin κ) = K_c·h·dz does
//!   not depend on κ while the edge force K_e·db does. db is taken as the exact integral of
//!   dz/sin κ over the disk, the arc length of the generator between the disk's faces
//!   ([`Cutter::arc_length`]): at a ball's tip 1/sin κ ∝ 1/sqrt(z) and the midpoint value
//!   dz/sin κ(z_j) would miss ~0.7·sqrt(dz/a_p) of the edge length (3.6 % of the edge force at
//!   400 disks); on a cylinder db = dz exactly;
//! * the immersion window [φ_st(z), φ_ex(z)] — a_p is measured from the tip and a_e from the
//!   wall *at that height*: the previous pass of the same tool, a_e beside this one, left its
//!   wall at R(z) − a_e, so up milling cuts φ ∈ [0, arccos(1 − a_e/R(z))] and down milling
//!   φ ∈ [π − arccos(1 − a_e/R(z)), π]; where a_e ≥ 2R(z) (the bottom of a ball at small a_p)
//!   the disk cuts a full slot [0, π]. Explicit entry/exit angles apply to every disk.
//!
//! Per (disk, tooth): ψ_i(z_j) ([`Cutter::tooth_angle`], constant lead or constant helix) and
//! its sine and cosine. Runout enters as today through R_i(z) = |R(z)·u(ψ_i(z)) + e(z)|.
//!
//! For a flat end mill sin κ = 1 and cos κ = 0 exactly and the window is the cut's, so every
//! kernel reproduces the cylindrical model bit for bit.

use crate::cut::Cut;
use crate::cutter::Cutter;

/// Fewest axial disks that resolve a non-cylindrical profile over the cut's axial depth: κ(z)
/// changes by at most 0.25° and the immersion window (entry and exit angle) by at most 0.1° per
/// disk, and R(z)
/// by at most 0.1 % of R (1 on a cylinder, where nothing varies along z); at most 2000. The
/// identification takes the larger of this and its helix-lag rule, so that its model resolves
/// the ball's tip like the simulation. (The per-disk window switches the edge force on at a
/// different angle on every disk: the discretisation error is first order in the disk count;
/// measured on the ball below, 0.25° per disk left a 4 % bias in K_tc of a round trip whose
/// truth had 2000 disks, 0.1° per disk 0.1 %.)
///
/// ```
/// use runout_core::{edge::min_disks, Cut, Cutter, MillingMode, RadiusProfile};
/// let ball = Cutter::new(6.0, vec![std::f64::consts::TAU / 3.0; 3], 30.0f64.to_radians(), 20.0, RadiusProfile::Ball).unwrap();
/// let cut = Cut::new(10400.0, 0.05, 0.2).unwrap().radial(0.125, MillingMode::Down, &ball).unwrap();
/// // κ(0.2 mm) = 21.0°, but the window sweeps from 180° (slot at the tip) to 27.9°: 1522 disks
/// let n = min_disks(&ball, &cut);
/// assert!(n > 1500 && n < 1540, "{n}");
/// assert_eq!(min_disks(&Cutter::flat(6.0, 3, 30.0f64.to_radians()).unwrap(), &cut), 1);
/// ```
pub fn min_disks(cutter: &Cutter, cut: &Cut) -> usize {
    let ap = cut.ap();
    if cutter.is_flat() || ap.is_nan() || ap <= 0.0 {
        return 1;
    }
    let dk = (cutter.lead_angle(ap) - cutter.lead_angle(0.0))
        .abs()
        .to_degrees();
    let dr = (cutter.radius_at(ap) - cutter.radius_at(0.0)).abs() / cutter.radius();
    // total variation of the entry and exit angles along z (sampled)
    let m = 256;
    let mut dw = 0.0f64;
    let mut prev = cut.immersion_at(cutter, 0.0);
    for q in 1..=m {
        let w = cut.immersion_at(cutter, ap * q as f64 / m as f64);
        dw += (w.0 - prev.0).abs().max((w.1 - prev.1).abs());
        prev = w;
    }
    let n = (dk / 0.25).max(dw.to_degrees() / 0.1).max(dr / 1e-3).ceil();
    if n.is_finite() {
        (n as usize).clamp(1, 2000)
    } else {
        2000
    }
}

/// Geometry of one axial disk.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disk {
    /// Mid-height z_j above the tip (mm).
    pub z: f64,
    /// Envelope radius R(z_j) (mm).
    pub radius: f64,
    /// sin κ(z_j).
    pub sin_kappa: f64,
    /// cos κ(z_j).
    pub cos_kappa: f64,
    /// Disk height dz (mm).
    pub dz: f64,
    /// Chip width / edge length of the disk, db = ∫ dz/sin κ over the disk (mm).
    pub db: f64,
    /// Entry immersion angle φ_st(z_j) (rad).
    pub entry: f64,
    /// Window width φ_ex(z_j) − φ_st(z_j) (rad).
    pub width: f64,
}

/// Geometry of one (disk, tooth) edge element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Element {
    /// ψ_i(z_j) (rad).
    pub psi: f64,
    /// cos ψ_i(z_j).
    pub cos_psi: f64,
    /// sin ψ_i(z_j).
    pub sin_psi: f64,
}

/// The per-disk and per-(disk, tooth) table (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeTable {
    teeth: usize,
    disks: Vec<Disk>,
    elements: Vec<Element>,
    flat: bool,
}

impl EdgeTable {
    /// Table of `disks` (≥ 1) disks over the cut's a_p for `cutter`.
    ///
    /// ```
    /// use runout_core::{edge::EdgeTable, Cut, Cutter, MillingMode, RadiusProfile};
    /// let ball = Cutter::new(6.0, vec![std::f64::consts::TAU / 3.0; 3], 30.0f64.to_radians(), 20.0, RadiusProfile::Ball).unwrap();
    /// let cut = Cut::new(10400.0, 0.05, 0.2).unwrap().radial(0.125, MillingMode::Down, &ball).unwrap();
    /// let t = EdgeTable::new(&ball, &cut, 4);
    /// let top = t.disk(3);
    /// // z = 0.175 mm: R(z) = sqrt(R² − (R − z)²), window arccos(1 − a_e/R(z))
    /// let r = (9.0f64 - 2.825f64.powi(2)).sqrt();
    /// assert!((top.radius - r).abs() < 1e-12);
    /// assert!((top.width - (1.0 - 0.125 / r).acos()).abs() < 1e-12);
    /// // the edge length of the disk is the arc of the sphere between its faces
    /// let kappa = |z: f64| ((3.0 - z) / 3.0).acos();
    /// assert!((top.db - 3.0 * (kappa(0.2) - kappa(0.15))).abs() < 1e-12);
    /// ```
    pub fn new(cutter: &Cutter, cut: &Cut, disks: usize) -> Self {
        let disks = disks.max(1);
        let k = cutter.teeth();
        let dz = cut.ap() / disks as f64;
        let disk_rows: Vec<Disk> = (0..disks)
            .map(|j| {
                let z = (j as f64 + 0.5) * dz;
                let (sk, ck) = cutter.lead_sin_cos(z);
                let (st, ex) = cut.immersion_at(cutter, z);
                Disk {
                    z,
                    radius: cutter.radius_at(z),
                    sin_kappa: sk,
                    cos_kappa: ck,
                    dz,
                    db: if cutter.is_flat() {
                        dz
                    } else {
                        cutter.arc_length(z + 0.5 * dz) - cutter.arc_length(z - 0.5 * dz)
                    },
                    entry: st,
                    width: ex - st,
                }
            })
            .collect();
        let elements = disk_rows
            .iter()
            .flat_map(|d| {
                (0..k).map(move |i| {
                    let psi = cutter.tooth_angle(i, d.z);
                    let (s, c) = psi.sin_cos();
                    Element {
                        psi,
                        cos_psi: c,
                        sin_psi: s,
                    }
                })
            })
            .collect();
        EdgeTable {
            teeth: k,
            flat: disk_rows
                .iter()
                .all(|d| d.sin_kappa == 1.0 && d.cos_kappa == 0.0),
            disks: disk_rows,
            elements,
        }
    }

    /// Number of teeth K.
    pub fn teeth(&self) -> usize {
        self.teeth
    }
    /// Number of disks.
    pub fn len(&self) -> usize {
        self.disks.len()
    }
    /// Always false (at least one disk).
    pub fn is_empty(&self) -> bool {
        self.disks.is_empty()
    }
    /// Disk j.
    pub fn disk(&self, j: usize) -> &Disk {
        &self.disks[j]
    }
    /// All disks, bottom up.
    pub fn disks(&self) -> &[Disk] {
        &self.disks
    }
    /// The K elements of disk j (tooth order).
    pub fn elements(&self, j: usize) -> &[Element] {
        &self.elements[j * self.teeth..(j + 1) * self.teeth]
    }
    /// True when κ = 90° on every disk (cylindrical kernel: the cheaper code path).
    pub fn is_flat(&self) -> bool {
        self.flat
    }
}
