//! One module per subcommand.

pub mod displacement;
pub mod simulate;
