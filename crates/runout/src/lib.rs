//! `runout` as a library: every job of the `runout` program (shank force, displacement, grind,
//! chip, …) as a function that takes a typed request and returns a typed report.
//!
//! Layers (README "Library"):
//!
//! * [`runout_core`] — model and methods, pure computation, no file I/O;
//! * [`runout_io`] — formats: configs, recordings, toolpaths, plots;
//! * **this crate** — the jobs: it reads the [`Source`]s a request names (paths or bytes in
//!   memory), runs the passes and the methods of core, and returns a report that serialises to
//!   the JSON the CLI prints (`schema` = `runout.<job>/<version>`, units in field names);
//! * `runout-cli` — parses flags, builds a request, calls a job, renders text/JSON/plots.
//!
//! The library prints nothing: progress goes through [`Progress`] (no-op: [`NoProgress`]).
//!
//! ```no_run
//! use runout::{shank, NoProgress, Source};
//! let request = shank::ForceRequest::new(Source::path("rec.csv"), Source::path("shank.toml"));
//! let report = shank::force(&request, &mut NoProgress)?;
//! println!("runout {:.2} µm at {:.1}°", report.runout.offset_um, report.runout.angle_deg);
//! # Ok::<(), anyhow::Error>(())
//! ```

pub mod answer;
pub mod batch;
pub mod case;
pub mod chip;
pub mod displacement;
pub mod grind;
pub mod html;
pub mod identify;
pub mod inspect;
pub mod job;
pub mod provenance;
pub mod schema;
pub mod shank;
pub mod simulate;
pub mod spill;
pub mod verdict;
pub mod words;

pub use job::{to_json, NoProgress, Progress, Report, Source};
pub use runout_core as core;
pub use runout_io as io;
