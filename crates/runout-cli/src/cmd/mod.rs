//! One module per subcommand.

pub mod batch;
pub mod chip;
pub mod displacement;
pub mod grind;
pub mod identify;
pub mod inspect;
pub mod install;
pub mod report;
pub mod shank;
pub mod simulate;
pub mod simulate_sensor;
