//! The integration tests of the `runout` command line, one test binary (one link) for all of them
//! (issue 13 item 8). Each module is a former `tests/<name>.rs`; filter with
//! `cargo test -p runout-cli --test cli <name>::`. Shared helpers (running the binary, examples,
//! reports without provenance) are in [`common`]; insta snapshots in `snapshots/`
//! (`cli__snapshots__<name>.snap`); input files in `../data/`.

mod answer;
mod answers;
mod bad_inputs;
mod ball_end;
mod batch;
mod batch_parquet;
mod batch_snapshot;
mod chip;
mod common;
mod config_words;
mod displacement;
mod flag_properties;
mod flag_vocabulary;
mod formats_identify;
mod formats_time_var;
mod grind;
mod guards;
mod html_report;
mod identify_chain;
mod identify_peaks;
mod identify_recording;
mod install;
mod issue20;
mod progress_tty;
mod provenance;
mod readme_commands;
mod shank;
mod simulate;
mod simulate_sensor;
mod snapshots;
