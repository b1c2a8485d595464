//! Provenance of this run (issue 21 item 6): the command line, and the name, size and SHA-256 of
//! every file named on it (a recording given as `FILE:SELECTOR` counts as `FILE`), hashed on a
//! background thread while the job runs (hashing a long recording costs about as much as reading
//! it once).
//!
//! The background thread runs under Linux's `SCHED_IDLE` policy: only on a core the job leaves
//! idle (between the reading's threads, during the fits), and a job thread that wakes takes the
//! core back at once. At nice 19 (before) it still held a core for a time slice when a parse
//! worker woke: +0.02 s on a 100 MB `identify`, against +0.01 s now (issue 18).
//!
//! A thread that runs only on idle cores may not run at all on a busy machine, so nothing ever
//! waits for it: it publishes a checkpoint ([`InputHashing`]'s clone) every 1 MiB, and when the
//! report is ready the writing thread stops it and finishes the hashing itself from the latest
//! checkpoint, at its own priority ([`settle`]).
//!
//! Every JSON report carries it as `provenance` ([`stamped_json`]) and every plot in its
//! metadata (`runout_io::plot::metadata`).

use runout::provenance::{InputHashing, Provenance, Stamped};
use runout::{Report, Source};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

static PENDING: Mutex<Option<Pending>> = Mutex::new(None);
static DONE: OnceLock<Outcome> = OnceLock::new();

/// Steps of [`InputHashing::step`] (64 KiB each) between two checkpoints: 1 MiB.
const CHECKPOINT_STEPS: u64 = 16;

/// The hashing under way: the command line and what the background thread shares with the
/// thread that will finish it.
struct Pending {
    args: Vec<String>,
    /// Inputs that can be read only once (pipes, FIFOs, devices): named, not hashed.
    streams: Vec<String>,
    shared: Arc<Shared>,
}

/// Between the background thread and the finishing one.
struct Shared {
    /// The latest checkpoint (the start, until the first is published), or the error that
    /// stopped the background thread. Held only to swap a value in or out.
    latest: Mutex<Result<InputHashing, String>>,
    /// Set when the finishing thread has taken over: the background thread stops.
    stop: AtomicBool,
}

impl Shared {
    /// Put `value` in `latest`; the value it held (the lock is held for the swap only).
    fn swap(&self, value: Result<InputHashing, String>) -> Result<InputHashing, String> {
        std::mem::replace(
            &mut *self.latest.lock().unwrap_or_else(|e| e.into_inner()),
            value,
        )
    }
}

/// What the hashing thread ended with.
#[derive(Debug)]
enum Outcome {
    /// [`start`] was not called (unit tests): no provenance, nothing to tell.
    NotStarted,
    /// Every input hashed.
    Done(Provenance),
    /// Why there is no provenance (an input could not be read to hash it, which names the file
    /// and the error).
    Failed(String),
}

/// Starts hashing the inputs named on `args` (program name first) and registers the plots'
/// metadata provider.
pub fn start(args: Vec<String>) {
    let named = named_inputs(&args);
    let streams = named.streams;
    let inputs: Vec<Source> = named.files.into_iter().map(Source::path).collect();
    let hashing = InputHashing::new(inputs);
    let shared = Arc::new(Shared {
        latest: Mutex::new(Ok(hashing.clone())),
        stop: AtomicBool::new(false),
    });
    let background = Arc::clone(&shared);
    std::thread::spawn(move || {
        lowest_priority();
        hash_in_background(hashing, &background);
    });
    *PENDING.lock().unwrap_or_else(|e| e.into_inner()) = Some(Pending {
        args,
        streams,
        shared,
    });
    runout_io::plot::metadata::set_provider(Some(Box::new(|| get().map(Provenance::summary_line))));
}

/// The background thread: steps through the inputs, publishing a checkpoint every
/// [`CHECKPOINT_STEPS`] steps, the finished hashing at the end or the error that stopped it;
/// returns early once the finishing thread has taken over.
fn hash_in_background(mut hashing: InputHashing, shared: &Shared) {
    // (the value replaced is dropped here, outside the lock)
    let publish = |value: Result<InputHashing, String>| drop(shared.swap(value));
    let mut steps = 0u64;
    while !shared.stop.load(Ordering::Relaxed) {
        match hashing.step() {
            Ok(true) => return publish(Ok(hashing)),
            Ok(false) => {
                steps += 1;
                if steps.is_multiple_of(CHECKPOINT_STEPS) {
                    publish(Ok(hashing.clone()));
                }
            }
            Err(e) => return publish(Err(e.to_string())),
        }
    }
}

/// The finishing side: stops the background thread and finishes the hashing on this thread
/// from the latest checkpoint (at once when the background thread has finished it).
fn settle(pending: Pending) -> Outcome {
    pending.shared.stop.store(true, Ordering::Relaxed);
    let latest = pending.shared.swap(Err(String::new()));
    match latest.and_then(|h| h.finish().map_err(|e| e.to_string())) {
        Ok(inputs) => Outcome::Done(
            Provenance::of_inputs(pending.args, inputs).with_not_hashed(pending.streams),
        ),
        Err(why) => Outcome::Failed(why),
    }
}

/// Puts the calling thread under Linux's `SCHED_IDLE` policy (it runs only when a core would
/// otherwise be idle), and at the lowest nice value where that is refused. On Linux the policy
/// and the nice value are per thread, so the job's own threads keep theirs. Best effort: a
/// failure leaves the thread as it was (the hash is the same either way).
fn lowest_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: gettid takes no pointer; setpriority reads and sets this thread's scheduling
    // attributes; sched_setscheduler reads `param`, which lives across the call.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::pid_t;
        libc::setpriority(libc::PRIO_PROCESS, tid as libc::id_t, 19);
        let param = libc::sched_param { sched_priority: 0 };
        libc::sched_setscheduler(tid, libc::SCHED_IDLE, &param);
    }
}

/// The provenance of this run (finishes the hashing); `None` if [`start`] was not called or
/// an input could not be read ([`stamped_json`] tells the user why).
pub fn get() -> Option<&'static Provenance> {
    match outcome() {
        Outcome::Done(p) => Some(p),
        Outcome::NotStarted | Outcome::Failed(_) => None,
    }
}

/// The hashing's result, settled once ([`settle`]); a failure is told on stderr then (once,
/// unless `--quiet`): the outputs go without provenance. It never waits for the background
/// thread: it reads the rest of the input files itself (regular files: [`named_inputs`] hashes
/// no FIFO or device).
fn outcome() -> &'static Outcome {
    DONE.get_or_init(|| {
        let Some(pending) = PENDING.lock().unwrap_or_else(|e| e.into_inner()).take() else {
            return Outcome::NotStarted;
        };
        let outcome = settle(pending);
        if let Some(w) = warning(&outcome) {
            crate::progress::warn(&w);
        }
        outcome
    })
}

/// What to tell the user when the outputs go without provenance.
fn warning(outcome: &Outcome) -> Option<String> {
    match outcome {
        Outcome::Failed(why) => Some(format!(
            "the outputs carry no provenance (command line, inputs' SHA-256): {why}"
        )),
        Outcome::Done(p) if !p.not_hashed.is_empty() => Some(format!(
            "the outputs' provenance names {} without a SHA-256: a pipe or device is read once, by \
             the job (give a file to have its content hashed)",
            p.not_hashed.join(", ")
        )),
        Outcome::NotStarted | Outcome::Done(_) => None,
    }
}

/// The report as `--json` writes it: the job's JSON plus `provenance`. Without a provenance
/// (an input could not be read to hash it: [`outcome`] has told the user) the job's JSON alone.
pub fn stamped_json<R: Report>(report: &R) -> serde_json::Result<String> {
    json_with(report, outcome())
}

/// The JSON of `report`, stamped with the provenance if there is one.
fn json_with<R: Report>(report: &R, outcome: &Outcome) -> serde_json::Result<String> {
    match outcome {
        Outcome::Done(provenance) => {
            Ok(serde_json::to_string_pretty(&Stamped { report, provenance })? + "\n")
        }
        Outcome::NotStarted | Outcome::Failed(_) => runout::to_json(report),
    }
}

/// Long names of the options whose value is a path the command WRITES (a file or a folder):
/// never an input, even when it exists already (its old content is not what the report comes
/// from; hashing it would also read a file the user may have made write-only). `--recording` is
/// `simulate`'s DynoWare output (recordings read by other commands are positional). `--summary`
/// (`batch`) is read first to resume, but it is the table the command writes.
pub const OUTPUT_FLAGS: &[&str] = &[
    "json",
    "out",
    "text",
    "html",
    "plot",
    "plot-dir",
    "map",
    "path-out",
    "recording",
    "summary",
    "parquet",
    "dir",
];

/// Long names of the options whose value is a path the command reads. Not used to choose the
/// inputs (every value not in [`OUTPUT_FLAGS`] that names an existing file is one); listed so
/// that every path option is classified, which a test checks on the whole command tree.
#[cfg(test)]
const INPUT_FLAGS: &[&str] = &["config", "sensor-frf", "probe", "generatrix", "nc"];

/// The inputs named on the command line (program name first; the command line of this program,
/// parsed again): the value of every argument, positional or option, other than the options in
/// [`OUTPUT_FLAGS`], that exists.
pub struct NamedInputs {
    /// Regular files, or `FILE:SELECTOR` whose `FILE` is one (hashed).
    pub files: Vec<String>,
    /// Those that can be read only once: a pipe such as `/dev/fd/63` from `<(…)`, standard
    /// input, a FIFO, a device (named only, never opened here: a second reader would take bytes
    /// from the job's).
    pub streams: Vec<String>,
}

/// [`NamedInputs`] of `args`, in command-line order, each once.
pub fn named_inputs(args: &[String]) -> NamedInputs {
    use clap::CommandFactory;
    let mut named = NamedInputs {
        files: Vec::new(),
        streams: Vec::new(),
    };
    let cmd = crate::Cli::command();
    // the command line was parsed by `main` before: this cannot fail
    let Ok(matches) = cmd.clone().try_get_matches_from(args) else {
        return named;
    };
    let mut values: Vec<(usize, &str)> = Vec::new();
    collect_values(&cmd, &matches, &mut values);
    values.sort_by_key(|&(index, _)| index);
    for (_, value) in values {
        // (`-`: standard input, where a command reads it)
        if value == "-" || runout_io::formats::is_stream(Path::new(value)) {
            push_once(&mut named.streams, value);
            continue;
        }
        let file = if Path::new(value).is_file() {
            Some(value)
        } else {
            value
                .rsplit_once(':')
                .map(|(file, _)| file)
                .filter(|f| Path::new(f).is_file())
        };
        if let Some(f) = file {
            push_once(&mut named.files, f);
        }
    }
    named
}

/// `value` appended to `list` unless it is there already.
fn push_once(list: &mut Vec<String>, value: &str) {
    if !list.iter().any(|g| g == value) {
        list.push(value.to_string());
    }
}

/// The values given on the command line to the arguments of `cmd` (and of the subcommand
/// chosen), except those of [`OUTPUT_FLAGS`], with their positions on the command line.
fn collect_values<'m>(
    cmd: &clap::Command,
    matches: &'m clap::ArgMatches,
    values: &mut Vec<(usize, &'m str)>,
) {
    for arg in cmd.get_arguments() {
        let id = arg.get_id().as_str();
        let output =
            !arg.is_positional() && arg.get_long().is_some_and(|l| OUTPUT_FLAGS.contains(&l));
        let given = matches.value_source(id) == Some(clap::parser::ValueSource::CommandLine);
        if output || !given || !arg.get_action().takes_values() {
            continue;
        }
        let (Ok(Some(raw)), Some(indices)) = (matches.try_get_raw(id), matches.indices_of(id))
        else {
            continue;
        };
        values.extend(indices.zip(raw).filter_map(|(i, v)| Some((i, v.to_str()?))));
    }
    if let Some((name, sub_matches)) = matches.subcommand() {
        if let Some(sub) = cmd.find_subcommand(name) {
            collect_values(sub, sub_matches, values);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(args: &[&str]) -> Vec<String> {
        args.iter().map(|a| a.to_string()).collect()
    }

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
        assert_eq!(named_inputs(&args).files, vec![s(&a), s(&m)]);
    }

    /// A FIFO (as a pipe from `<(…)` or standard input) named on the command line is never
    /// opened for hashing: a second reader would take its bytes from the job. The provenance
    /// names it without a hash and the user is told.
    #[cfg(target_os = "linux")]
    #[test]
    fn pipes_and_fifos_are_named_not_hashed() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("rec.fifo");
        let c = std::ffi::CString::new(fifo.display().to_string()).unwrap();
        // SAFETY: a NUL-terminated path; mkfifo only creates the node
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let cfg = dir.path().join("cut.toml");
        std::fs::write(&cfg, "teeth = 4").unwrap();
        let s = |p: &Path| p.display().to_string();
        let args: Vec<String> = vec![
            "runout".into(),
            "identify".into(),
            s(&fifo),
            s(&fifo),
            "--config".into(),
            s(&cfg),
        ];
        // (opening the FIFO to read it would block here: nobody writes to it)
        let named = named_inputs(&args);
        assert_eq!(named.files, vec![s(&cfg)]);
        assert_eq!(named.streams, vec![s(&fifo)]);
        let hashed = InputHashing::new(named.files.into_iter().map(Source::path).collect());
        let p =
            Provenance::of_inputs(args, hashed.finish().unwrap()).with_not_hashed(named.streams);
        let json = serde_json::to_value(&p).unwrap();
        assert_eq!(json["not_hashed"][0], s(&fifo));
        assert_eq!(json["inputs"].as_array().unwrap().len(), 1);
        let told = warning(&Outcome::Done(p)).expect("the user is told");
        assert!(told.contains(&s(&fifo)) && told.contains("pipe"), "{told}");
        // without such inputs the field is left out and nothing is said
        let plain = Provenance::of_inputs(["runout"], vec![]);
        assert!(serde_json::to_value(&plain)
            .unwrap()
            .get("not_hashed")
            .is_none());
        assert!(warning(&Outcome::Done(plain)).is_none());
    }

    /// The old content of an output is not an input, however the flag is written (`--json F`,
    /// `--html=F`, a hidden alias); inputs come in command-line order.
    #[test]
    fn existing_outputs_are_not_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let file = |name: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, "x").unwrap();
            p.display().to_string()
        };
        let (cfg, rec, frf) = (file("cut.toml"), file("rec.txt"), file("frf.csv"));
        let (json, html, plot) = (file("out.json"), file("out.html"), file("old.svg"));
        let plots = dir.path().join("plots");
        std::fs::create_dir(&plots).unwrap();
        let args = strings(&[
            "runout",
            "identify",
            "--config",
            &cfg,
            "--json",
            &json,
            &rec,
            &format!("--html={html}"),
            "--sensor-frf",
            &frf,
            "--plot-dir",
            &plots.display().to_string(),
        ]);
        assert_eq!(
            named_inputs(&args).files,
            vec![cfg.clone(), rec.clone(), frf]
        );
        let (csv, dwd) = (file("old.csv"), file("old.txt"));
        let args = strings(&[
            "runout",
            "simulate",
            "--quiet",
            "--config",
            &cfg,
            "--out",
            &csv,
            "--recording",
            &dwd,
            "--json",
            &json,
            "--plot",
            &plot,
        ]);
        assert_eq!(named_inputs(&args).files, vec![cfg.clone()]);
        let (nc, probe, out_nc, path_csv) = (
            file("in.nc"),
            file("probe.csv"),
            file("out.nc"),
            file("path.csv"),
        );
        let args = strings(&[
            "runout",
            "grind",
            "compensate",
            "--out",
            &out_nc,
            "--nc",
            &nc,
            "--probe",
            &probe,
            "--path-out",
            &path_csv,
        ]);
        assert_eq!(named_inputs(&args).files, vec![nc, probe]);
    }

    /// Every option whose value is a path is classified as written ([`OUTPUT_FLAGS`]) or read
    /// ([`INPUT_FLAGS`]), on every subcommand: a new output flag missing from [`OUTPUT_FLAGS`]
    /// fails here instead of having its old file hashed as an input. Every name listed is an
    /// option of some command (no stale entry), and in one list only.
    #[test]
    fn every_path_option_is_classified() {
        use clap::CommandFactory;
        fn walk(
            cmd: &clap::Command,
            path: &str,
            found: &mut Vec<String>,
            errors: &mut Vec<String>,
        ) {
            for arg in cmd.get_arguments() {
                let Some(long) = arg.get_long() else { continue };
                found.push(long.to_string());
                let is_path = arg.get_value_parser().type_id()
                    == clap::builder::ValueParser::path_buf().type_id();
                if is_path && !OUTPUT_FLAGS.contains(&long) && !INPUT_FLAGS.contains(&long) {
                    errors.push(format!("{path} --{long}"));
                }
            }
            for sub in cmd.get_subcommands() {
                walk(sub, &format!("{path} {}", sub.get_name()), found, errors);
            }
        }
        let (mut found, mut errors) = (Vec::new(), Vec::new());
        walk(&crate::Cli::command(), "runout", &mut found, &mut errors);
        assert!(
            errors.is_empty(),
            "path options neither in OUTPUT_FLAGS nor in INPUT_FLAGS (provenance.rs): {errors:?}"
        );
        for name in OUTPUT_FLAGS.iter().chain(INPUT_FLAGS) {
            assert!(found.iter().any(|f| f == name), "--{name} is no option");
        }
        assert!(OUTPUT_FLAGS.iter().all(|o| !INPUT_FLAGS.contains(o)));
    }

    fn report() -> runout::batch::BatchReport {
        runout::batch::BatchReport {
            schema: "runout.batch/1".into(),
            summary: "s.csv".into(),
            files: 1,
            skipped: 0,
            analysed: 1,
            ok: 1,
            failed: Vec::new(),
            rows: 1,
            threads: 1,
            elapsed_s: 0.5,
            recordings_per_s: 2.0,
        }
    }

    /// A failed hashing gives the report without provenance and a warning naming the file and
    /// the error (it once called `stamped_json` again, forever).
    #[test]
    fn without_provenance_the_report_is_written_alone_and_the_user_told() {
        let dir = tempfile::tempdir().unwrap();
        let missing = Source::path(dir.path().join("gone.txt"));
        let e = Provenance::new(["runout"], &[missing]).unwrap_err();
        let failed = Outcome::Failed(e.to_string());
        let json = json_with(&report(), &failed).unwrap();
        assert_eq!(json, runout::to_json(&report()).unwrap());
        assert!(!json.contains("provenance"), "{json}");
        let w = warning(&failed).unwrap();
        assert!(
            w.contains("no provenance") && w.contains("gone.txt") && w.contains("cannot read"),
            "{w}"
        );
        let done = Outcome::Done(Provenance::new(["runout", "x"], &[]).unwrap());
        let v: serde_json::Value =
            serde_json::from_str(&json_with(&report(), &done).unwrap()).unwrap();
        assert_eq!(v["provenance"]["command_line"][1], "x");
        assert_eq!(warning(&done), None);
    }

    fn pending(inputs: Vec<Source>) -> (Pending, InputHashing) {
        let hashing = InputHashing::new(inputs);
        let shared = Arc::new(Shared {
            latest: Mutex::new(Ok(hashing.clone())),
            stop: AtomicBool::new(false),
        });
        let args = vec!["runout".to_string(), "x".to_string()];
        let streams = Vec::new();
        (
            Pending {
                args,
                streams,
                shared,
            },
            hashing,
        )
    }

    /// The hashing is finished by the thread that needs it, whatever the background thread did:
    /// nothing (a thread that a busy machine never schedules), part of it (stopped while it
    /// runs), or all of it; the hashes are those of `InputFile::of` each time.
    #[test]
    fn the_waiting_thread_finishes_the_hashing_itself() {
        let dir = tempfile::tempdir().unwrap();
        let files: Vec<Source> = [3 << 20, 10, 0]
            .iter()
            .enumerate()
            .map(|(i, &len)| {
                let p = dir.path().join(format!("r{i}.txt"));
                std::fs::write(&p, (0..len).map(|k| (k % 253) as u8).collect::<Vec<u8>>()).unwrap();
                Source::path(p)
            })
            .collect();
        let expected: Vec<_> = files
            .iter()
            .map(|f| runout::provenance::InputFile::of(f).unwrap())
            .collect();
        let hashes = |o: Outcome| match o {
            Outcome::Done(p) => {
                assert_eq!(p.command_line, ["runout", "x"]);
                p.inputs
            }
            other => panic!("{other:?}"),
        };
        // never scheduled
        let (p, _) = pending(files.clone());
        assert_eq!(hashes(settle(p)), expected);
        // stopped after its first checkpoint (the rest read by the finishing thread)
        let (p, mut h) = pending(files.clone());
        for _ in 0..CHECKPOINT_STEPS + 3 {
            h.step().unwrap();
        }
        *p.shared.latest.lock().unwrap() = Ok(h.clone());
        assert_eq!(hashes(settle(p)), expected);
        // running while the report is settled, and run to its end
        for wait in [false, true] {
            let (p, h) = pending(files.clone());
            let shared = Arc::clone(&p.shared);
            let t = std::thread::spawn(move || hash_in_background(h, &shared));
            if wait {
                t.join().unwrap();
            }
            assert_eq!(hashes(settle(p)), expected);
        }
    }

    /// An input the background thread could not read: no provenance, and the reason names it.
    #[test]
    fn a_read_error_of_the_background_thread_is_the_outcome() {
        let dir = tempfile::tempdir().unwrap();
        let (p, h) = pending(vec![Source::path(dir.path().join("gone.txt"))]);
        hash_in_background(h, &p.shared);
        match settle(p) {
            Outcome::Failed(why) => assert!(why.contains("gone.txt"), "{why}"),
            other => panic!("{other:?}"),
        }
    }

    /// `stamped_json` without provenance (here: never started) returns, within a bound (a
    /// recursion would spin here for ever; the bound turns it into a failure).
    #[test]
    fn stamped_json_without_provenance_returns() {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || tx.send(stamped_json(&report()).unwrap()));
        let json = rx
            .recv_timeout(std::time::Duration::from_secs(60))
            .expect("stamped_json did not return within 60 s");
        assert_eq!(json, runout::to_json(&report()).unwrap());
    }
}
