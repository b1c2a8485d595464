//! One module per subcommand.

pub mod chip;
pub mod simulate;
