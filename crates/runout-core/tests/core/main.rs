//! The integration tests of `runout-core`, one test binary (one link) for all of them (issue 13).
//! Each module is a former `tests/<name>.rs`; filter with `cargo test -p runout-core --test core <name>::`.
//! Proptest regression seeds: `tests/proptest-regressions/<module>.txt` (proptest's `SourceParallel`
//! lookup for a module of a `main.rs`: the `main.rs` directory is replaced by `proptest-regressions`).

mod chip_lookback;
mod chip_models;
mod chip_vectors;
mod displacement;
mod doc_citations;
mod force_kernel;
mod force_simulation;
mod general_end_mills;
mod grind_interp;
mod grind_probe;
mod grind_sim;
mod identify_chain;
mod identify_coverage;
mod identify_mean_force;
mod identify_model;
mod identify_properties;
mod identify_roundtrip;
mod identify_seed003;
mod model;
mod plausibility;
mod shank;
mod signal;
