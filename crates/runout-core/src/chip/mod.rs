//! Instantaneous undeformed chip thickness (IUCT) with runout.
//!
//! Every chip-thickness model implements [`ChipThickness`]: given a height z it prepares a
//! [`ChipAtHeight`] evaluator (precomputed radii, feeds between teeth…) that returns h (mm) of
//! tooth i at immersion φ in steady 3-axis straight feed. The force simulation is generic over
//! this interface, so every model can drive it.

mod arc;
pub mod closed_form;
pub mod compare;
pub mod compensation;
pub mod exact;
pub mod kinematics;
mod lanes;
pub mod lookback;
mod straight;

pub use arc::{ArcAtHeight, ArcChip};
pub use closed_form::{
    arc_at, arc_iuct, closed_forms, closed_forms_at, equivalent_at, equivalent_iuct, pass_terms,
    ClosedForms, EquivalentParams, PassTerms,
};
pub use compensation::{
    calibration_grid, fit_compensation, fit_compensation_to, CalibrationPoint, CompensationFit,
};
pub use exact::{
    crossing_at, exact_at, exact_at_time, exact_iuct, ray_crossing, ExactIuct, NewtonOptions, Ray,
    RayCrossing, RayTime,
};
pub use kinematics::{
    CircularFeed, ClPath, ClPoint, ConstantSwing, EdgeState, HeightGeometry, JointPath, JointPoint,
    Pose, RigidStep, SpindlePoint, SpindleSense, StraightFeed, ToolKinematics, ToolMotion, Vec3,
};
pub use lookback::{EquivalentEvaluator, HeightLookBack, LookBack};
pub use straight::{
    straight_feed_kinematics, EquivalentAtHeight, EquivalentChip, ExactAtHeight, ExactChip,
};

/// A chip-thickness model for steady 3-axis straight feed.
///
/// ```
/// use runout_core::{ArcChip, ChipThickness, Cutter, Runout};
/// let cutter = Cutter::flat(10.0, 4, 0.0).unwrap();
/// let model = ArcChip::new(&cutter, &Runout::none(), 0.1).unwrap();
/// // no runout: h = f_z·sin φ
/// let h = model.thickness(0, 0.0, 30f64.to_radians());
/// assert!((h - 0.05).abs() < 1e-12);
/// ```
pub trait ChipThickness: Sync {
    /// Per-height evaluator.
    type AtHeight: ChipAtHeight;

    /// Short model name (`arc`, `exact`, `equivalent`).
    fn name(&self) -> &'static str;

    /// Prepare the evaluator for axial height `z` (mm from the tool tip).
    fn at_height(&self, z: f64) -> Self::AtHeight;

    /// Convenience: h (mm) of `tooth` at height `z` and immersion `phi` (rad). Slow path
    /// (prepares the height each call); loops should use [`ChipThickness::at_height`].
    fn thickness(&self, tooth: usize, z: f64, phi: f64) -> f64 {
        let (s, c) = phi.sin_cos();
        self.at_height(z).thickness(tooth, phi, s, c)
    }
}

/// Chip-thickness evaluator at one axial height.
pub trait ChipAtHeight: Send + Sync {
    /// h ≥ 0 (mm) of tooth `tooth` at immersion `phi` (rad); `sin_phi`, `cos_phi` are passed
    /// because the caller already has them.
    fn thickness(&self, tooth: usize, phi: f64, sin_phi: f64, cos_phi: f64) -> f64;
}
