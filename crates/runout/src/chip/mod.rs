//! Chip-thickness jobs (methods.md §2): the models against the exact IUCT on a case set
//! (`compare`), and h along the motion of one case (`eval`).

mod compare;
mod eval;
pub mod render;

pub use compare::{
    compare, CaseReport, CompareReport, CompareRequest, EquivalentModel, FittedK, Metrics,
    MetricsDefinitions, ModelErrors, PooledThroughput, Throughput,
};
pub use eval::{eval, ChipModel, EvalDetail, EvalReport, EvalRequest};

use crate::job::Source;
use anyhow::{bail, Result};
use runout_io::config::chip::{parse_case_specs, resolve_case, ChipCase, ChipConfigError};
use std::path::PathBuf;

/// Read and resolve every case of `config` (toolpaths and joint tables relative to its folder).
pub fn read_cases(config: &Source) -> Result<Vec<ChipCase>, ChipConfigError> {
    let file = config.name().to_string();
    let text = config.read_text().map_err(|e| ChipConfigError::Parse {
        file: file.clone(),
        message: match e.line() {
            Some(l) => format!("line {l}: {}", e.message),
            None => e.message,
        },
    })?;
    parse_case_specs(&file, &text)?
        .into_iter()
        .map(|s| resolve_case(&file, config.dir(), s))
        .collect()
}

/// The cases whose name contains `filter` (all without one); none is an error.
fn select(cases: Vec<ChipCase>, filter: Option<&str>, file: &str) -> Result<Vec<ChipCase>> {
    let chosen: Vec<ChipCase> = match filter {
        Some(f) => cases.into_iter().filter(|c| c.name.contains(f)).collect(),
        None => cases,
    };
    if chosen.is_empty() {
        bail!("{file}: no case matches --case {:?}", filter.unwrap_or(""));
    }
    Ok(chosen)
}

/// The case file and every file its cases name (toolpaths, joint tables; relative to the case
/// file): what an output must not overwrite.
fn case_inputs(config: &Source, cases: &[ChipCase]) -> Vec<PathBuf> {
    let base = config.dir();
    let mut v: Vec<PathBuf> = config
        .as_path()
        .map(|p| p.to_path_buf())
        .into_iter()
        .collect();
    for c in cases {
        for f in [&c.spec.toolpath, &c.spec.joints].into_iter().flatten() {
            v.push(base.join(f));
        }
    }
    v
}
