//! One module per subcommand.

pub mod grind;
pub mod simulate;
