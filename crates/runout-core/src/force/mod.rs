//! Mechanistic milling-force simulation with runout (Altintas), methods.md §4.1 and §6.
//!
//! The flutes are cut into `disks` axial slices of height dz = a_p / disks at mid-heights
//! z_j = (j + ½)·dz. At spindle angle θ tooth i's slice j has immersion φ = θ + ψ_i(z_j)
//! (`conventions.md`). Where φ lies in [φ_st, φ_ex] and h > 0:
//!
//! dF_t = K_tc·h·dz + K_te·dz,  dF_r = K_rc·h·dz + K_re·dz,  dF_a = K_ac·h·dz + K_ae·dz
//!
//! Forces **acting on the workpiece** in the workpiece frame (x feed, y feed-normal, z up) are the
//! reaction of Altintas' forces on the tool:
//!
//! F_x = Σ ( dF_t·cos φ + dF_r·sin φ ),  F_y = Σ ( −dF_t·sin φ + dF_r·cos φ ),  F_z = −Σ dF_a
//!
//! and the spindle torque is T = Σ dF_t·R_i(z_j). Edge forces act only where h > 0.

#[doc(hidden)]
pub mod baseline;
pub(crate) mod kernel;
mod peaks;

pub use peaks::{tooth_peaks, ToothPeak};

use crate::chip::{ArcChip, ChipThickness};
use crate::coefficients::CuttingCoefficients;
use crate::cut::Cut;
use crate::cutter::Cutter;
use crate::edge::EdgeTable;
use crate::error::{positive, ParamError};
use crate::runout::Runout;
use rayon::prelude::*;
use std::any::Any;
use std::f64::consts::TAU;

/// Angular sampling and axial discretisation of a simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    /// Number of spindle revolutions simulated.
    pub revolutions: f64,
    /// Angular step (rad).
    pub step: f64,
    /// Number of axial disks.
    pub disks: usize,
}

impl Sampling {
    /// Largest number of angle samples one simulation holds in memory
    /// ([`crate::limits::MAX_SAMPLES`]).
    pub const MAX_SAMPLES: usize = crate::limits::MAX_SAMPLES;

    /// `revolutions` turns at `step_deg` degrees per sample with `disks` axial disks.
    pub fn new(revolutions: f64, step_deg: f64, disks: usize) -> Result<Self, ParamError> {
        crate::limits::positive_at_most(
            "revolutions",
            revolutions,
            crate::limits::MAX_REVOLUTIONS,
            "revolutions",
        )?;
        positive("step_deg", step_deg)?;
        if step_deg > 90.0 {
            return Err(ParamError::new(
                "step_deg",
                "an angular step in (0, 90] degrees",
                crate::limits::show(step_deg),
            ));
        }
        crate::limits::count("disks", disks, crate::limits::MAX_DISKS)?;
        let samples = revolutions * 360.0 / step_deg;
        if samples > Self::MAX_SAMPLES as f64 {
            return Err(ParamError::new(
                "revolutions",
                format!(
                    "at most {} samples in one simulation (revolutions·360/step_deg)",
                    Self::MAX_SAMPLES
                ),
                format!(
                    "{} revolutions at {}° = {samples:.3e} samples",
                    crate::limits::show(revolutions),
                    crate::limits::show(step_deg)
                ),
            ));
        }
        Ok(Sampling {
            revolutions,
            step: step_deg.to_radians(),
            disks,
        })
    }

    /// Number of angle samples: ⌈revolutions·2π/step⌉ (the end point excluded).
    pub fn samples(&self) -> usize {
        ((self.revolutions * TAU / self.step) - 1e-9)
            .ceil()
            .max(1.0) as usize
    }
}

/// Everything a force simulation needs.
#[derive(Debug, Clone)]
pub struct ForceModel {
    /// The cutter.
    pub cutter: Cutter,
    /// Its runout.
    pub runout: Runout,
    /// Cutting conditions.
    pub cut: Cut,
    /// Cutting coefficients.
    pub coefficients: CuttingCoefficients,
}

/// Simulated forces: one entry per angle sample.
#[derive(Debug, Clone, Default)]
pub struct ForceSeries {
    /// Spindle angle θ (rad): tooth 0's tip is at immersion θ.
    pub angle: Vec<f64>,
    /// Time (s) = θ/ω.
    pub time: Vec<f64>,
    /// F_x on the workpiece (N).
    pub fx: Vec<f64>,
    /// F_y on the workpiece (N).
    pub fy: Vec<f64>,
    /// F_z on the workpiece (N).
    pub fz: Vec<f64>,
    /// Spindle torque (N·m).
    pub torque: Vec<f64>,
    /// Chip thickness (mm) per tooth at the lowest disk: `chip[i][n]`.
    pub chip: Vec<Vec<f64>>,
    /// Per tooth, the largest chip thickness over all disks and samples (mm).
    pub max_chip: Vec<f64>,
    /// Per tooth, the largest |F_xy| (N) of that tooth's own contribution.
    pub own_peak_fxy: Vec<f64>,
}

impl ForceSeries {
    /// Resultant |F_xy| (N) per sample.
    pub fn fxy(&self) -> Vec<f64> {
        self.fx
            .iter()
            .zip(&self.fy)
            .map(|(x, y)| x.hypot(*y))
            .collect()
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.angle.len()
    }
    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.angle.is_empty()
    }
    /// Mean of F_x, F_y, F_z (N) and torque (N·m) over the samples.
    pub fn means(&self) -> [f64; 4] {
        let n = self.len().max(1) as f64;
        let m = |v: &[f64]| v.iter().sum::<f64>() / n;
        [m(&self.fx), m(&self.fy), m(&self.fz), m(&self.torque)]
    }
}

impl ForceModel {
    /// Simulate the forces with chip model `chip` over `sampling`.
    ///
    /// Per disk the table [`EdgeTable`] gives R(z), κ(z), db = dz/sin κ and the immersion window
    /// (module docs of [`crate::edge`]). With h the chip thickness of `chip` in the radial plane,
    /// the normal chip is h·sin κ and (Lee & Altintas 1996; Engin & Altintas 2001)
    ///
    /// dF_t = (K_tc·h sin κ + K_te)·db,  dF_r = (K_rc·h sin κ + K_re)·db,  dF_a = (K_ac·h sin κ + K_ae)·db,
    ///
    /// with db = dz/sin κ, evaluated as K_c·h·dz + K_e·db (the shear part integrated exactly
    /// over the disk, db the disk's exact edge length, [`crate::edge`]),
    ///
    /// projected on the workpiece frame through κ (the (r, a) pair rotated by κ in the plane of
    /// the axis and the tooth's radius; κ = 90° gives the cylindrical formulas of the module docs):
    ///
    /// F_x = Σ [dF_t cos φ + (dF_r sin κ − dF_a cos κ) sin φ],
    /// F_y = Σ [−dF_t sin φ + (dF_r sin κ − dF_a cos κ) cos φ],
    /// F_z = −Σ (dF_r cos κ + dF_a sin κ).
    ///
    /// `ForceSeries::chip` and `max_chip` are the normal chip h·sin κ.
    ///
    /// ```
    /// use runout_core::*;
    /// let cutter = Cutter::flat(10.0, 4, 0.0).unwrap();
    /// let cut = Cut::new(3240.0, 0.08, 1.0).unwrap().radial(2.0, MillingMode::Down, &cutter).unwrap();
    /// let k = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
    /// let model = ForceModel { cutter: cutter.clone(), runout: Runout::none(), cut, coefficients: k };
    /// let chip = ArcChip::new(&cutter, &Runout::none(), 0.08).unwrap();
    /// let s = model.simulate(&chip, &Sampling::new(1.0, 0.01, 1).unwrap());
    /// let peak = s.fxy().into_iter().fold(0.0, f64::max);
    /// assert!((peak - 247.361).abs() < 0.02);
    /// ```
    ///
    /// Evaluated by the shared kernel (`force::kernel`, issue 18) that also computes the basis
    /// sums of [`crate::identify::RevolutionModel`]: engagement, chip and sin/cos φ of every
    /// element once, contracted here with the coefficients per element (the forces above, in
    /// the same arithmetic as before the kernel was shared, so results are unchanged bit for bit). The arc chip ([`ArcChip`]) is evaluated in SIMD lanes; any other chip model
    /// through its scalar [`crate::ChipAtHeight`] evaluator, one call per lane.
    pub fn simulate<C: ChipThickness + 'static>(
        &self,
        chip: &C,
        sampling: &Sampling,
    ) -> ForceSeries {
        let table = EdgeTable::new(&self.cutter, &self.cut, sampling.disks);
        if table.is_flat() {
            self.simulate_table::<C, false>(chip, sampling, &table)
        } else {
            self.simulate_table::<C, true>(chip, sampling, &table)
        }
    }

    /// Always the κ(z) kernel, also on a cylinder: for verification and benchmarks (on a flat
    /// end mill it equals [`ForceModel::simulate`], which takes the cheaper path there).
    pub fn simulate_general<C: ChipThickness + 'static>(
        &self,
        chip: &C,
        sampling: &Sampling,
    ) -> ForceSeries {
        let table = EdgeTable::new(&self.cutter, &self.cut, sampling.disks);
        self.simulate_table::<C, true>(chip, sampling, &table)
    }

    fn simulate_table<C: ChipThickness + 'static, const GENERAL: bool>(
        &self,
        chip: &C,
        sampling: &Sampling,
        table: &EdgeTable,
    ) -> ForceSeries {
        let k = table.teeth();
        let sim = kernel::SimConsts {
            radius: table
                .disks()
                .iter()
                .flat_map(|d| (0..k).map(move |i| self.runout.tooth_radius(&self.cutter, i, d.z)))
                .collect(),
            kc: self.coefficients,
        };
        if let Some(arc) = (chip as &dyn Any).downcast_ref::<ArcChip>() {
            let mut lanes = kernel::ArcLanes {
                k,
                feed: Vec::with_capacity(table.len() * k * k),
                dr: Vec::with_capacity(table.len() * k * k),
                dnx: Vec::new(),
                dny: Vec::new(),
            };
            for d in table.disks() {
                let ev = arc.at_height(d.z);
                for i in 0..k {
                    for m in 1..=k {
                        lanes.feed.push(ev.feed(i, m));
                        lanes.dr.push(ev.radius_difference(i, m));
                    }
                }
            }
            self.run_kernel::<_, GENERAL>(&lanes, sampling, table, &sim)
        } else {
            let lanes =
                kernel::ScalarLanes(table.disks().iter().map(|d| chip.at_height(d.z)).collect());
            self.run_kernel::<_, GENERAL>(&lanes, sampling, table, &sim)
        }
    }

    /// Blocks of [`CHUNK`] samples in parallel (rayon), each through the shared kernel.
    fn run_kernel<L: kernel::LaneChip, const GENERAL: bool>(
        &self,
        lanes: &L,
        sampling: &Sampling,
        table: &EdgeTable,
        sim: &kernel::SimConsts,
    ) -> ForceSeries {
        let k = table.teeth();
        let n = sampling.samples();
        let omega = self.cut.omega();
        let arch = pulp::Arch::new();
        // The series' columns, written in place by the blocks (issue 18: no intermediate
        // row-major buffers and gathers; `vec![0.0; n]` maps zero pages that the blocks fault
        // in once, by the thread that fills them).
        let column = || vec![0.0f64; n];
        let (mut angle, mut time, mut fx, mut fy, mut fz, mut torque) =
            (column(), column(), column(), column(), column(), column());
        let mut chip: Vec<Vec<f64>> = (0..k).map(|_| column()).collect();
        let blocks: Vec<Vec<&mut [f64]>> = {
            let mut cols: Vec<std::slice::ChunksMut<f64>> = [
                &mut angle,
                &mut time,
                &mut fx,
                &mut fy,
                &mut fz,
                &mut torque,
            ]
            .into_iter()
            .chain(chip.iter_mut())
            .map(|v| v.chunks_mut(CHUNK))
            .collect();
            (0..n.div_ceil(CHUNK))
                .map(|_| cols.iter_mut().filter_map(|c| c.next()).collect())
                .collect()
        };
        let opts = kernel::Options {
            edge_in_window: false,
            np: 0,
        };
        let (max_chip, own_peak) = blocks
            .into_par_iter()
            .enumerate()
            .map_init(
                // one grid and one set of accumulators per worker, reused block after block
                || {
                    (
                        kernel::Grid::new(std::iter::empty(), sampling.step, false),
                        kernel::Acc::new(0, GENERAL, 0, Some(k)),
                    )
                },
                |(grid, acc), (c, mut cols)| {
                    let len = cols[0].len();
                    grid.fill((0..len).map(|q| sampling.step * (c * CHUNK + q) as f64));
                    acc.reset_sim(kernel::padded(len));
                    kernel::dispatch::<L, GENERAL, true>(
                        arch,
                        table,
                        lanes,
                        grid,
                        0..table.len(),
                        opts,
                        Some(sim),
                        acc,
                    );
                    let stride = acc.stride;
                    let f = &acc.force;
                    cols[0].copy_from_slice(&grid.theta[..len]);
                    for (t, a) in cols[1].iter_mut().zip(&grid.theta[..len]) {
                        *t = a / omega;
                    }
                    for r in 0..3 {
                        cols[2 + r].copy_from_slice(&f[r * stride..r * stride + len]);
                    }
                    for (m, v) in cols[5].iter_mut().zip(&f[3 * stride..3 * stride + len]) {
                        *m = v * 1e-3; // N·mm → N·m
                    }
                    for i in 0..k {
                        cols[6 + i].copy_from_slice(&acc.chip[i * stride..i * stride + len]);
                    }
                    let own_peak: Vec<f64> = (0..k)
                        .map(|i| {
                            let x = &acc.own[2 * i * stride..2 * i * stride + len];
                            let y = &acc.own[(2 * i + 1) * stride..(2 * i + 1) * stride + len];
                            peaks::max_hypot(x, y)
                        })
                        .collect();
                    let max_chip: Vec<f64> = acc
                        .max_chip
                        .iter()
                        .map(|v| v.iter().fold(0.0f64, |a, b| a.max(*b)))
                        .collect();
                    (max_chip, own_peak)
                },
            )
            .reduce(
                || (vec![0.0; k], vec![0.0; k]),
                |a, b| {
                    (
                        a.0.iter().zip(&b.0).map(|(x, y)| x.max(*y)).collect(),
                        a.1.iter().zip(&b.1).map(|(x, y)| x.max(*y)).collect(),
                    )
                },
            );
        ForceSeries {
            time,
            fx,
            fy,
            fz,
            torque,
            angle,
            chip,
            max_chip,
            own_peak_fxy: own_peak,
        }
    }
}

/// Samples per parallel block of a simulation.
const CHUNK: usize = 2048;
