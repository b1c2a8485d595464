//! One module per subcommand.

pub mod displacement;
pub mod grind;
pub mod identify;
pub mod simulate;
