//! One module per subcommand.

pub mod chip;
pub mod grind;
pub mod simulate;
