//! One module per subcommand.

pub mod displacement;
pub mod chip;
pub mod grind;
pub mod shank;
pub mod simulate;
