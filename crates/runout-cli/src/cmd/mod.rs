//! One module per subcommand.

pub mod grind;
pub mod identify;
pub mod simulate;
