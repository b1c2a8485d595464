//! Files of the grinding compensation (methods.md §5): the probe table, edge / wheel-path
//! points, the compensated path, and the plots. Rows are identified by their **file line
//! number** in every error.

mod csv_table;
mod edge_csv;
mod path_csv;
pub mod plot;
mod probe_csv;

pub use csv_table::CsvError;
pub use edge_csv::{read_edge_csv, EdgeTable};
pub use path_csv::write_path_csv;
pub use probe_csv::read_probe_csv;
