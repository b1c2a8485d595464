//! Shank jobs (seed 002, methods.md §3): stiffness of the beam model, force + runout from a
//! recording of two displacement sensors per direction, static calibration of K_δ.

#![allow(non_snake_case)] // field names carry their units as the JSON does (`stiffness_N_per_um`)

mod calibrate;
mod config;
mod force;
pub mod render;

pub use calibrate::{calibrate, CalibrateRequest, CalibrationReport, LoadPointFrom};
pub use force::{
    force, force_to, AxisForce, AxisValidation, BeamReport, Correction, Dynamics, ForcePlotData,
    ForceReport, ForceRequest, OutputReport, PairReport, RunoutReport, SensorRunout, SeriesFormat,
    SpectralResonance, SpindleReport, Thinned, ToothHarmonic, Validation,
};

use crate::job::Report;
use anyhow::{Context, Result};
use runout_core::shank::{LoadPoint, ShankBeam};
use schemars::JsonSchema;
use serde::Serialize;

/// `runout shank stiffness`: the beam and its options.
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessRequest {
    /// Young's modulus E (GPa).
    pub modulus_gpa: f64,
    /// Shank diameter d (mm).
    pub diameter_mm: f64,
    /// Tool length from the holder face l_tool (mm).
    pub tool_length_mm: f64,
    /// Sensor I height from the holder face (mm).
    pub l1_mm: f64,
    /// Sensor II height from the holder face (mm).
    pub l2_mm: f64,
    /// Load at mid axial depth: a_p (mm); default at the tip.
    pub ap_mm: Option<f64>,
    /// Holder rotational stiffness k_θ (N·m/rad); default rigid.
    pub holder_stiffness_Nm_per_rad: Option<f64>,
    /// Density (kg/m³); default from the modulus (carbide/steel).
    pub density_kg_per_m3: Option<f64>,
}

/// The beam's inputs as reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct BeamInputs {
    pub modulus_gpa: f64,
    pub diameter_mm: f64,
    pub tool_length_mm: f64,
    pub l1_mm: f64,
    pub l2_mm: f64,
}

/// `runout.shank.stiffness/1`: K_δ of the beam model and its first bending mode.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StiffnessReport {
    /// `runout.shank.stiffness/1`
    #[schemars(extend("const" = "runout.shank.stiffness/1"))]
    pub schema: String,
    pub first_bending_mode_hz: f64,
    pub density_kg_per_m3: f64,
    pub usable_bandwidth_hz: f64,
    pub bandwidth_criterion: String,
    pub stiffness_N_per_um: f64,
    pub stiffness_N_per_mm: f64,
    pub second_moment_mm4: f64,
    pub load_point_mm: f64,
    pub holder_stiffness_Nm_per_rad: Option<f64>,
    pub inputs: BeamInputs,
    pub formula: String,
}

impl Report for StiffnessReport {
    const SCHEMA: &'static str = "runout.shank.stiffness/1";
}

/// K_δ = 6EI/[l_II²(3l_tool − l_II) − l_I²(3l_tool − l_I)] and the first bending mode.
pub fn stiffness(req: &StiffnessRequest) -> Result<StiffnessReport> {
    let mut beam = ShankBeam::new(
        req.modulus_gpa,
        req.diameter_mm,
        req.tool_length_mm,
        req.l1_mm,
        req.l2_mm,
    )?;
    if let Some(ap) = req.ap_mm {
        beam = beam.with_load_point(LoadPoint::MidDepth { axial_depth_mm: ap })?;
    }
    if let Some(k) = req.holder_stiffness_Nm_per_rad {
        beam = beam.with_holder_stiffness_nm_per_rad(k)?;
    }
    let density = req.density_kg_per_m3.unwrap_or_else(|| {
        runout_core::shank::default_density_kg_per_m3(beam.modulus_n_per_mm2 / 1e3)
    });
    let f1 = beam
        .first_bending_mode_hz(density)
        .context("--density-kg-per-m3")?;
    let mode = runout_core::chain::SensorMode::new(f1, 0.03, 1.0)?;
    let band = runout_core::shank::usable_bandwidth_hz(
        &runout_core::chain::AxisChain::Modes(vec![mode]),
        None,
        10.0 * f1,
    );
    Ok(StiffnessReport {
        schema: StiffnessReport::SCHEMA.into(),
        first_bending_mode_hz: f1,
        density_kg_per_m3: density,
        usable_bandwidth_hz: band,
        bandwidth_criterion:
            "|H(f) - 1| <= 10 % for one mode at f1, damping 0.03 (docs/shank.md)".into(),
        stiffness_N_per_um: beam.stiffness_n_per_um(),
        stiffness_N_per_mm: beam.stiffness_n_per_mm(),
        second_moment_mm4: beam.second_moment_mm4(),
        load_point_mm: beam.load_distance_mm(),
        holder_stiffness_Nm_per_rad: beam.holder_rotational_stiffness_nmm_per_rad.map(|k| k / 1e3),
        inputs: BeamInputs {
            modulus_gpa: beam.modulus_n_per_mm2 / 1e3,
            diameter_mm: beam.diameter_mm,
            tool_length_mm: beam.tool_length_mm,
            l1_mm: beam.l1_mm,
            l2_mm: beam.l2_mm,
        },
        formula: "K = 6EI / [l2^2(3a - l2) - l1^2(3a - l1) + 6EI(l2 - l1)a/k_theta], I = pi d^4/64 (docs/methods.md §3.1)".into(),
    })
}
