//! `grind check`: the simulation check of methods.md §5.5 — a bar clamped with a known offset +
//! tilt is probed with noise, the edge is ground without compensation, with the seed's bilinear
//! scheme and with the first-harmonic scheme, and the finished edge is measured.

use super::{edge, EdgeSpec, GeneratedEdge};
use crate::job::Report;
use anyhow::Result;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use runout_core::grind::*;
use schemars::JsonSchema;
use serde::Serialize;

/// The axis offset x, y (µm, bar frame) of a runout of length `rho_um` (µm) in the direction
/// `angle_deg` (deg, from x towards y): (ρ cos λ, ρ sin λ), methods.md §5.1.
pub fn offset_xy_um(rho_um: f64, angle_deg: f64) -> [f64; 2] {
    let (s, c) = angle_deg.to_radians().sin_cos();
    [rho_um * c, rho_um * s]
}

/// `runout grind check`.
#[derive(Debug, Clone)]
pub struct CheckRequest {
    pub bar_diameter_mm: f64,
    /// Axis offset at u = 0, bar frame (µm).
    pub offset_um: [f64; 2],
    /// Axis tilt (µm/mm).
    pub tilt_um_per_mm: [f64; 2],
    pub layers: usize,
    pub angles: usize,
    /// Probed u range (mm from the tip).
    pub u_range_mm: [f64; 2],
    /// Probe noise σ (µm).
    pub noise_um: f64,
    pub draws: usize,
    pub seed: u64,
    pub range: RangePolicy,
    pub edge: GeneratedEdge,
}

/// The inputs as reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct CheckInputs {
    pub bar_diameter_mm: f64,
    pub offset_um: [f64; 2],
    pub tilt_um_per_mm: [f64; 2],
    pub layers: usize,
    pub angles: usize,
    pub u_range_mm: [f64; 2],
    pub noise_um: f64,
    pub draws: usize,
    pub seed: u64,
    pub edge: String,
    pub edge_points: usize,
    pub outside_probed_range: String,
}

/// Errors without compensation.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Uncompensated {
    pub radius_error_um: f64,
    pub profile_error_um: f64,
}

/// Errors of one scheme (means over draws).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SchemeCheck {
    pub interpolation_rms_um: f64,
    pub interpolation_max_um: f64,
    pub radius_error_after_um: f64,
    pub profile_error_after_um: f64,
}

/// `runout.grind.check/2`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct CheckReport {
    /// `runout.grind.check/2`
    #[schemars(extend("const" = "runout.grind.check/2"))]
    pub schema: String,
    /// The result first: the edge's radius error after the first-harmonic compensation against
    /// the uncompensated one, the status and its reasons (issue 21). A simulation: the status
    /// says whether this probing plan identifies the bar axis well enough for the compensation
    /// to help (`not identified` when the compensated edge is no better than the uncompensated
    /// one); how large an error is acceptable is the user's tolerance, a verdict, not a status.
    pub answer: crate::answer::Answer,
    pub inputs: CheckInputs,
    pub definitions: String,
    pub uncompensated: Uncompensated,
    pub bilinear: SchemeCheck,
    pub first_harmonic: SchemeCheck,
}

impl crate::answer::Answered for CheckReport {
    fn answer(&self) -> &crate::answer::Answer {
        &self.answer
    }
}

impl Report for CheckReport {
    const SCHEMA: &'static str = "runout.grind.check/2";
}

/// Mean over draws of the grind check for each scheme.
fn mean_checks(
    bar: &SimulatedBar,
    grid: &(Vec<f64>, Vec<f64>),
    edge: &EdgeLine,
    sigma: f64,
    req: &CheckRequest,
) -> Result<[GrindCheck; 2]> {
    let mut rng = StdRng::seed_from_u64(req.seed);
    let normal = Normal::new(0.0, sigma)?;
    let zero = GrindCheck {
        interpolation_rms: 0.0,
        interpolation_max: 0.0,
        radius_error_before: 0.0,
        radius_error_after: 0.0,
        profile_before: 0.0,
        profile_after: 0.0,
    };
    let mut acc = [zero; 2];
    let w = 1.0 / req.draws as f64;
    for _ in 0..req.draws {
        let map = DeviationMap::new(&bar.probe(&grid.0, &grid.1, || normal.sample(&mut rng))?);
        for (k, scheme) in [Scheme::Bilinear, Scheme::FirstHarmonic]
            .into_iter()
            .enumerate()
        {
            let f = Interpolator::new(&map, scheme, req.range);
            let c = grind_check(bar, edge, &compensate(&f, &map.axis, edge, None)?);
            let s = &mut acc[k];
            s.interpolation_rms += w * c.interpolation_rms;
            s.interpolation_max += w * c.interpolation_max;
            s.radius_error_before += w * c.radius_error_before;
            s.radius_error_after += w * c.radius_error_after;
            s.profile_before += w * c.profile_before;
            s.profile_after += w * c.profile_after;
        }
    }
    Ok(acc)
}

/// Probe a simulated bar, grind its edge with each scheme, and measure the result.
pub fn check(req: &CheckRequest) -> Result<CheckReport> {
    let d = req.bar_diameter_mm;
    let (off, tilt) = (req.offset_um, req.tilt_um_per_mm);
    let sigma = req.noise_um * 1e-3;
    runout_core::limits::count("--draws", req.draws, runout_core::limits::MAX_DRAWS)?;
    let [u0, u1] = req.u_range_mm;
    let bar = SimulatedBar::new(
        d / 2.0,
        [off[0] * 1e-3, off[1] * 1e-3],
        [tilt[0] * 1e-3, tilt[1] * 1e-3],
    )?;
    let grid = uniform_grid(u0, u1, req.layers, req.angles)?;
    let spec = EdgeSpec::Generated(req.edge);
    let (edge, _) = edge(&spec, d, u1)?;
    runout_core::limits::work(
        "--draws",
        "evaluations (draws × probe points × edge points)",
        req.draws as f64 * (req.layers * req.angles) as f64 * edge.points.len() as f64,
        runout_core::limits::MAX_EVALUATIONS,
    )?;
    let [bil, har] = mean_checks(&bar, &grid, &edge, sigma, req)?;
    let um = |x: f64| x * 1e3;
    let row = |c: &GrindCheck| SchemeCheck {
        interpolation_rms_um: um(c.interpolation_rms),
        interpolation_max_um: um(c.interpolation_max),
        radius_error_after_um: um(c.radius_error_after),
        profile_error_after_um: um(c.profile_after),
    };
    let answer = {
        use crate::answer::{Answer, CrossCheck, Quantity};
        let (before, after) = (um(har.radius_error_before), um(har.radius_error_after));
        let ok = after < before;
        Answer {
            status: Answer::status_of(ok, true).into(),
            method: format!(
                "simulation: a bar clamped with the given offset and tilt, probed at {} layers × \
                 {} angles with noise σ = {:.2} µm ({} draws), compensated by the first \
                 harmonic per layer (docs/methods.md §5.5)",
                req.layers,
                req.angles,
                um(sigma),
                req.draws
            ),
            runout: None,
            results: vec![
                Quantity::identified("radius error after compensation", "µm", after, None),
                Quantity::identified(
                    "profile error after compensation",
                    "µm",
                    um(har.profile_after),
                    None,
                ),
                Quantity::identified("radius error without compensation", "µm", before, None),
            ],
            reasons: if ok {
                Vec::new()
            } else {
                vec![format!(
                    "the compensated edge ({after:.2} µm) is no better than the uncompensated one \
                     ({before:.2} µm): this probing plan does not identify the bar axis (noise \
                     too large for the clamping error); probe more layers and angles"
                )]
            },
            warnings: Vec::new(),
            cross_checks: vec![CrossCheck {
                estimate: "bilinear interpolation of the deviation map".into(),
                values: vec![Quantity::cross_check(
                    "radius error after compensation",
                    "µm",
                    um(bil.radius_error_after),
                    None,
                )],
                why_it_may_differ: "interpolates the measured deviations (noise and form \
                                    included) instead of fitting the rigid axis"
                    .into(),
            }],
        }
    };
    Ok(CheckReport {
        schema: CheckReport::SCHEMA.into(),
        answer,
        inputs: CheckInputs {
            bar_diameter_mm: d,
            offset_um: off,
            tilt_um_per_mm: tilt,
            layers: req.layers,
            angles: req.angles,
            u_range_mm: [u0, u1],
            noise_um: um(sigma),
            draws: req.draws,
            seed: req.seed,
            edge: spec.name(),
            edge_points: edge.points.len(),
            outside_probed_range: crate::words::snake(&req.range),
        },
        definitions: "interpolation error ε − e(u)·n against the true axis; radius error max |r − r_nominal| and profile error max − min of the finished edge about the real axis (ball: about the real ball centre); averages over draws".into(),
        uncompensated: Uncompensated {
            radius_error_um: um(har.radius_error_before),
            profile_error_um: um(har.profile_before),
        },
        bilinear: row(&bil),
        first_harmonic: row(&har),
    })
}
