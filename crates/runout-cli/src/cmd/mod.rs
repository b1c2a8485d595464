//! One module per subcommand.

pub mod shank;
pub mod simulate;
