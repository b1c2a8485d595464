//! Issue 14 item 5: error causes printed once. The rule (`runout_io::report`): a `Display`
//! includes the text of its cause or exposes it via `source()`, never both; and the chain
//! printer the CLI uses prints each cause once even for an error type that breaks the rule.

use runout_io::recording::{ReadOptions, Recording, RecordingError};
use runout_io::report::{chain_message, io_problem};
use std::error::Error;

/// The message printed for `e` has each cause once, and ends with `hint`.
fn printed_once(e: &(dyn Error + 'static), cause: &str, hint: &str) {
    let m = chain_message(e);
    assert_eq!(m.matches(cause).count(), 1, "{m}");
    assert!(m.ends_with(hint), "{m}");
    // the rule itself: either the text or the source, not both
    if let Some(s) = e.source() {
        assert!(
            !e.to_string().contains(&s.to_string()),
            "{e} and its source {s}"
        );
    }
}

#[test]
fn os_errors_of_every_reader_are_printed_once_with_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path();
    let missing = folder.join("missing.csv");
    let is_dir = "Is a directory (os error 21)";
    let not_found = "No such file or directory (os error 2)";

    // recordings (the reported `cannot read: Is a directory (os error 21): Is a directory …`)
    let e = Recording::read(folder, &ReadOptions::default()).unwrap_err();
    assert!(matches!(e, RecordingError::Io { .. }));
    printed_once(&e, is_dir, "expected a file, got a folder");
    let e = Recording::read(&missing, &ReadOptions::default()).unwrap_err();
    printed_once(
        &e,
        not_found,
        "check the path (relative paths start at the current folder)",
    );

    // every whole-file reader: text files (configs, toolpaths, NC, tables), displacement
    // tables, FRF tables, peak tables, chip case files
    let e = runout_io::textfile::read_text(folder).unwrap_err();
    printed_once(&e, "is a folder", "expected a file");
    let e = runout_io::textfile::read_text(&missing).unwrap_err();
    printed_once(
        &e,
        not_found,
        "check the path (relative paths start at the current folder)",
    );
    let e = runout_io::displacement::read_height_table(folder).unwrap_err();
    printed_once(&e, "is a folder", "expected a CSV file");
    let e = runout_io::displacement::read_height_table(&missing).unwrap_err();
    printed_once(
        &e,
        not_found,
        "check the path (relative paths start at the current folder)",
    );
    let e = runout_io::frf::read_frf(&missing).unwrap_err();
    printed_once(
        &e,
        not_found,
        "check the path (relative paths start at the current folder)",
    );
    let e = runout_io::peak_table::read_peak_table(folder).unwrap_err();
    printed_once(&e, "is a folder", "expected a file");
    let e = runout_io::config::chip::read_cases(&missing).unwrap_err();
    printed_once(
        &e,
        not_found,
        "check the path (relative paths start at the current folder)",
    );
    let e = runout_io::toolpath::read_toolpath(folder).unwrap_err();
    printed_once(&e, "is a folder", "expected a file");
}

#[test]
fn io_errors_in_messages_carry_no_source() {
    let io = || std::io::Error::from(std::io::ErrorKind::PermissionDenied);
    let errors: Vec<Box<dyn Error>> = vec![
        Box::new(RecordingError::Io {
            file: "a.csv".into(),
            error: io(),
        }),
        Box::new(runout_io::toolpath::ToolpathError::Io {
            file: "a.apt".into(),
            error: io(),
        }),
        Box::new(runout_io::config::chip::ChipConfigError::Io {
            file: "a.toml".into(),
            error: io(),
        }),
    ];
    for e in errors {
        assert!(e.source().is_none(), "{e}");
        assert!(
            e.to_string().ends_with("check the file's permissions"),
            "{e}"
        );
    }
    assert_eq!(
        io_problem(&std::io::Error::other("disk on fire")),
        "disk on fire",
        "no advice for an unknown kind"
    );
}

/// A wrapper that names its cause and also returns it from `source()` (as `anyhow`'s context
/// of an error type breaking the rule would): the printer shows the cause once, and keeps
/// distinct causes in order.
#[test]
fn the_chain_printer_drops_repeated_causes_only() {
    #[derive(Debug)]
    struct Wrap(&'static str, Box<dyn Error + 'static>, bool);
    impl std::fmt::Display for Wrap {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            if self.2 {
                write!(f, "{}: {}", self.0, self.1)
            } else {
                write!(f, "{}", self.0)
            }
        }
    }
    impl Error for Wrap {
        fn source(&self) -> Option<&(dyn Error + 'static)> {
            Some(self.1.as_ref())
        }
    }
    let root = || Box::new(std::io::Error::other("root cause")) as Box<dyn Error>;
    let doubled = Wrap("reading x.csv", root(), true);
    assert_eq!(chain_message(&doubled), "reading x.csv: root cause");
    let plain = Wrap("outer", Box::new(Wrap("middle", root(), false)), false);
    assert_eq!(chain_message(&plain), "outer: middle: root cause");
}

/// A bad value given as a flag is named as the flag (where the user typed it), a bad value in a
/// file as the file's key.
#[test]
fn config_errors_name_the_flag_or_the_key() {
    use runout_io::config::ConfigError;
    let key = |source: &str, key: &str| {
        ConfigError::Key {
            source_name: source.into(),
            key: key.into(),
            message: "expected > 0, got -1".into(),
        }
        .to_string()
    };
    assert_eq!(
        key("command line", "fz_mm"),
        "--fz-mm (key `fz_mm`): expected > 0, got -1"
    );
    assert_eq!(
        key("command line", "from_s/to_s"),
        "--from-s/--to-s (key `from_s/to_s`): expected > 0, got -1"
    );
    assert_eq!(
        key("cut.toml", "fz_mm"),
        "cut.toml: key `fz_mm`: expected > 0, got -1"
    );
}
