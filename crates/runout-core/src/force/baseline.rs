//! The force kernel as it was before issue 18 (one scalar loop per sample, every tooth × disk
//! tested): kept as the baseline of the `force_kernel` benchmark and as the oracle of the
//! kernel's equivalence tests (`tests/core/force_simulation.rs`). Not for production use.

use super::{ForceModel, ForceSeries, Sampling};
use crate::angle::wrap_tau;
use crate::chip::{ChipAtHeight, ChipThickness};
use crate::edge::EdgeTable;
use rayon::prelude::*;

/// [`ForceModel::simulate`] as implemented before issue 18 (baseline).
pub fn simulate<C: ChipThickness>(
    model: &ForceModel,
    chip: &C,
    sampling: &Sampling,
) -> ForceSeries {
    let table = EdgeTable::new(&model.cutter, &model.cut, sampling.disks);
    if table.is_flat() {
        simulate_table::<C, false>(model, chip, sampling, &table)
    } else {
        simulate_table::<C, true>(model, chip, sampling, &table)
    }
}

/// [`ForceModel::simulate_general`] as implemented before issue 18 (baseline).
pub fn simulate_general<C: ChipThickness>(
    model: &ForceModel,
    chip: &C,
    sampling: &Sampling,
) -> ForceSeries {
    let table = EdgeTable::new(&model.cutter, &model.cut, sampling.disks);
    simulate_table::<C, true>(model, chip, sampling, &table)
}

/// Per (disk, tooth) runout-dependent radius next to the shared [`EdgeTable`] geometry.
struct Slice {
    cos_psi: f64,
    sin_psi: f64,
    psi: f64,
    radius: f64,
}

/// Per-disk constants of the kernel.
#[derive(Clone, Copy)]
struct DiskConst {
    entry: f64,
    width: f64,
    sin_kappa: f64,
    cos_kappa: f64,
    dz: f64,
    db: f64,
}

/// The kernel; `GENERAL = false` only when κ = 90° on every disk (then sin κ = 1, cos κ = 0
/// and db = dz, and the κ terms are left out of the inner loop).
fn simulate_table<C: ChipThickness, const GENERAL: bool>(
    model: &ForceModel,
    chip: &C,
    sampling: &Sampling,
    table: &EdgeTable,
) -> ForceSeries {
    let k = model.cutter.teeth();
    let n = sampling.samples();
    let omega = model.cut.omega();

    let evaluators: Vec<C::AtHeight> = table.disks().iter().map(|d| chip.at_height(d.z)).collect();
    let consts: Vec<DiskConst> = table
        .disks()
        .iter()
        .map(|d| DiskConst {
            entry: d.entry,
            width: d.width,
            sin_kappa: d.sin_kappa,
            cos_kappa: d.cos_kappa,
            dz: d.dz,
            db: d.db,
        })
        .collect();
    let slices: Vec<Slice> = table
        .disks()
        .iter()
        .enumerate()
        .flat_map(|(j, d)| {
            table
                .elements(j)
                .iter()
                .enumerate()
                .map(move |(i, el)| Slice {
                    cos_psi: el.cos_psi,
                    sin_psi: el.sin_psi,
                    psi: el.psi,
                    radius: model.runout.tooth_radius(&model.cutter, i, d.z),
                })
        })
        .collect();
    let kc = model.coefficients;

    let mut out = vec![[0.0f64; 4]; n];
    let mut chip_out = vec![0.0f64; n * k];
    const CHUNK: usize = 2048;
    let (max_chip, own_peak) = out
        .par_chunks_mut(CHUNK)
        .zip(chip_out.par_chunks_mut(CHUNK * k))
        .enumerate()
        .map(|(c, (out, chip_out))| {
            let mut max_chip = vec![0.0f64; k];
            let mut own_peak = vec![0.0f64; k];
            let mut own = vec![[0.0f64; 2]; k];
            for (q, o) in out.iter_mut().enumerate() {
                let theta = sampling.step * (c * CHUNK + q) as f64;
                let (st_theta, ct_theta) = theta.sin_cos();
                let mut f = [0.0f64; 4];
                own.iter_mut().for_each(|v| *v = [0.0; 2]);
                for (j, (ev, dc)) in evaluators.iter().zip(&consts).enumerate() {
                    let dz = dc.dz;
                    let st = dc.entry;
                    let width = dc.width;
                    for (i, sl) in slices[j * k..(j + 1) * k].iter().enumerate() {
                        let rel = wrap_tau(theta + sl.psi - st);
                        if rel > width {
                            continue;
                        }
                        let phi = st + rel;
                        // sin/cos of θ+ψ by the addition theorem: no trig in the inner loop.
                        let s = st_theta * sl.cos_psi + ct_theta * sl.sin_psi;
                        let co = ct_theta * sl.cos_psi - st_theta * sl.sin_psi;
                        let h_arc = ev.thickness(i, phi, s, co);
                        let h = if GENERAL { h_arc * dc.sin_kappa } else { h_arc };
                        if j == 0 {
                            chip_out[q * k + i] = h;
                        }
                        if h <= 0.0 {
                            continue;
                        }
                        max_chip[i] = max_chip[i].max(h);
                        let (ft, frad, fax) = if GENERAL {
                            // K_c·(h sin κ)·db integrates to K_c·h_arc·dz (h_arc = h/sin κ)
                            let hz = h_arc * dz;
                            let db = dc.db;
                            let ft = kc.ktc * hz + kc.kte * db;
                            let fr = kc.krc * hz + kc.kre * db;
                            let fa = kc.kac * hz + kc.kae * db;
                            (
                                ft,
                                fr * dc.sin_kappa - fa * dc.cos_kappa,
                                fr * dc.cos_kappa + fa * dc.sin_kappa,
                            )
                        } else {
                            (
                                (kc.ktc * h + kc.kte) * dz,
                                (kc.krc * h + kc.kre) * dz,
                                (kc.kac * h + kc.kae) * dz,
                            )
                        };
                        let dx = ft * co + frad * s;
                        let dy = -ft * s + frad * co;
                        f[0] += dx;
                        f[1] += dy;
                        f[2] -= fax;
                        f[3] += ft * sl.radius;
                        own[i][0] += dx;
                        own[i][1] += dy;
                    }
                }
                f[3] *= 1e-3; // N·mm → N·m
                *o = f;
                for (p, v) in own_peak.iter_mut().zip(&own) {
                    *p = p.max(v[0].hypot(v[1]));
                }
            }
            (max_chip, own_peak)
        })
        .reduce(
            || (vec![0.0; k], vec![0.0; k]),
            |a, b| {
                (
                    a.0.iter().zip(&b.0).map(|(x, y)| x.max(*y)).collect(),
                    a.1.iter().zip(&b.1).map(|(x, y)| x.max(*y)).collect(),
                )
            },
        );

    let angle: Vec<f64> = (0..n).map(|q| sampling.step * q as f64).collect();
    let time = angle.iter().map(|a| a / omega).collect();
    let chip = (0..k)
        .map(|i| (0..n).map(|q| chip_out[q * k + i]).collect())
        .collect();
    ForceSeries {
        time,
        fx: out.iter().map(|v| v[0]).collect(),
        fy: out.iter().map(|v| v[1]).collect(),
        fz: out.iter().map(|v| v[2]).collect(),
        torque: out.iter().map(|v| v[3]).collect(),
        angle,
        chip,
        max_chip,
        own_peak_fxy: own_peak,
    }
}
