//! The integration tests of `runout-io`, one test binary (one link) for all of them (issue 13).
//! Each module is a former `tests/<name>.rs`; filter with `cargo test -p runout-io --test io <name>::`.
//! Data stays in `tests/data` and `tests/fixtures` (paths from `CARGO_MANIFEST_DIR`).
//! Proptest regression seeds: `tests/proptest-regressions/<module>.txt` (proptest's `SourceParallel`
//! lookup for a module of a `main.rs`: the `main.rs` directory is replaced by `proptest-regressions`).

mod displacement;
mod error_chain;
mod formats;
mod formats_mutated;
mod formats_parquet;
mod formats_structured;
mod gcode;
mod grind_csv;
mod issue14_regressions;
mod mutated_inputs;
mod plots;
mod recording;
mod toolpath;
