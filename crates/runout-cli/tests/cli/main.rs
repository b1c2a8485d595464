//! The integration tests of the `runout` command line, one test binary (one link) for all of them
//! (issue 13 item 8). Each module is a former `tests/<name>.rs`; filter with
//! `cargo test -p runout-cli --test cli <name>::`. Shared helpers (running the binary, examples,
//! reports without provenance) are in [`common`]; insta snapshots in `snapshots/`
//! (`cli__snapshots__<name>.snap`); input files in `../data/`.

mod answer;
mod bad_inputs;
mod ball_end;
mod batch;
mod chip;
mod common;
mod displacement;
mod flag_properties;
mod flag_vocabulary;
mod formats_identify;
mod grind;
mod html_report;
mod identify_chain;
mod identify_peaks;
mod identify_recording;
mod install;
mod issue20;
mod readme_commands;
mod shank;
mod simulate;
mod simulate_sensor;
mod snapshots;
