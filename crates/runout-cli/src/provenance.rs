//! Provenance of this run (issue 21 item 6): the command line, and the name, size and SHA-256 of
//! every file named on it (a recording given as `FILE:SELECTOR` counts as `FILE`), hashed on a
//! background thread while the job runs (hashing a long recording costs about as much as reading
//! it once). The thread runs at the lowest scheduling priority (nice 19 on Linux), so it takes
//! the cores only when the job leaves one idle — during its fits, which run on one core — instead
//! of slowing the reading, which keeps both busy (issue 18: −0.05 s on a 100 MB `identify`).
//! Every JSON report carries it
//! as `provenance` ([`stamped_json`]) and every plot in its metadata
//! (`runout_io::plot::metadata`).

use runout::provenance::{Provenance, Stamped};
use runout::{Report, Source};
use std::path::Path;
use std::sync::{Mutex, OnceLock};
use std::thread::JoinHandle;

static PENDING: Mutex<Option<JoinHandle<Option<Provenance>>>> = Mutex::new(None);
static DONE: OnceLock<Option<Provenance>> = OnceLock::new();

/// Starts hashing the inputs named on `args` (program name first) and registers the plots'
/// metadata provider.
pub fn start(args: Vec<String>) {
    let inputs: Vec<Source> = input_files(&args).into_iter().map(Source::path).collect();
    let handle = std::thread::spawn(move || {
        lowest_priority();
        Provenance::new(args, &inputs).ok()
    });
    *PENDING.lock().unwrap_or_else(|e| e.into_inner()) = Some(handle);
    runout_io::plot::metadata::set_provider(Some(Box::new(|| get().map(Provenance::summary_line))));
}

/// Lowers the calling thread's scheduling priority to the lowest (nice 19): on Linux the nice
/// value is per thread, so the job's own threads keep theirs. Best effort: a failure leaves the
/// priority as it was (the hash is the same either way).
fn lowest_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: gettid and setpriority take no pointers; they only read and set this thread's
    // scheduling attributes.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        libc::setpriority(libc::PRIO_PROCESS, tid, 19);
    }
}

/// The provenance of this run (waits for the hashing to finish); `None` if [`start`] was not
/// called or an input could not be read (the job reports that itself).
pub fn get() -> Option<&'static Provenance> {
    DONE.get_or_init(|| {
        let handle = PENDING.lock().unwrap_or_else(|e| e.into_inner()).take()?;
        handle.join().ok().flatten()
    })
    .as_ref()
}

/// The report as `--json` writes it: the job's JSON plus `provenance`.
pub fn stamped_json<R: Report>(report: &R) -> serde_json::Result<String> {
    match get() {
        Some(provenance) => {
            Ok(serde_json::to_string_pretty(&Stamped { report, provenance })? + "\n")
        }
        None => crate::provenance::stamped_json(report),
    }
}

/// The files named on the command line: every argument (or `--flag=value` value) that is an
/// existing file, or `FILE:SELECTOR` whose `FILE` is one.
pub fn input_files(args: &[String]) -> Vec<String> {
    let mut files: Vec<String> = Vec::new();
    for arg in args.iter().skip(1) {
        let value = match arg.split_once('=') {
            Some((flag, v)) if flag.starts_with("--") => v,
            _ => arg.as_str(),
        };
        let candidate = if Path::new(value).is_file() {
            Some(value)
        } else {
            value
                .rsplit_once(':')
                .map(|(file, _)| file)
                .filter(|f| Path::new(f).is_file())
        };
        if let Some(f) = candidate {
            if !files.iter().any(|g| g == f) {
                files.push(f.to_string());
            }
        }
    }
    files
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_files_are_the_existing_files_named() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.csv");
        let m = dir.path().join("d.mat");
        std::fs::write(&a, "x").unwrap();
        std::fs::write(&m, "x").unwrap();
        let s = |p: &Path| p.display().to_string();
        let args: Vec<String> = vec![
            "runout".into(),
            "identify".into(),
            s(&a),
            format!("{}:600", s(&m)),
            format!("--config={}", s(&a)),
            "--json".into(),
            s(&dir.path().join("out.json")),
            "--rpm".into(),
            "3000".into(),
        ];
        assert_eq!(input_files(&args), vec![s(&a), s(&m)]);
    }
}
