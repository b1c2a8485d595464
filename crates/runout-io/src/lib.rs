//! # runout-io
//!
//! Readers and writers for `runout`: configuration files with units, recordings, toolpaths,
//! result tables and plots. All conversion to the library's conventions
//! (`docs/conventions.md`) happens here, at the boundary.
#![warn(missing_docs)]

pub mod config;
pub mod displacement;
pub mod displacement_plot;
pub mod export;
pub mod formats;
pub mod frf;
pub mod gcode;
pub mod grind;
pub mod lineplot;
mod located;
pub mod mapped;
pub mod peak_table;
pub mod plot;
pub mod recording;
pub mod report;
pub(crate) mod table;
pub mod textfile;
pub mod toolpath;
pub mod units;

pub use located::LocatedError;
