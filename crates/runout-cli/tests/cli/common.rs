//! Helpers shared by the CLI integration tests (each test crate uses a subset).
#![allow(dead_code)]

use assert_cmd::Command;
use std::path::PathBuf;

/// The `runout` binary of this build, without backtraces in its error output.
pub fn runout() -> Command {
    let mut c = Command::cargo_bin("runout").unwrap();
    c.env("RUST_BACKTRACE", "0");
    c
}

/// A file under the repository's `examples/` folder, e.g. `example("chip/flank.apt")`.
pub fn example(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(path)
}

/// `runout identify` on the bundled example (the README's main job) without its outputs: run
/// from the repository root, followed by the output flags a test wants.
pub const IDENTIFY_EXAMPLE_INPUTS: [&str; 5] = [
    "identify",
    "examples/identify/cut_fz0.05.txt",
    "examples/identify/cut_fz0.08.txt",
    "--config",
    "examples/identify/cut.toml",
];

/// Seed 003's cut as `runout simulate` flags: K 4, D 10 mm, 3240 rpm, f_z 0.08 mm, a_p 1 mm,
/// a_e 2 mm down-milling.
pub const SEED003_CUT: [&str; 15] = [
    "simulate",
    "--teeth",
    "4",
    "--diameter-mm",
    "10",
    "--rpm",
    "3240",
    "--fz-mm",
    "0.08",
    "--ap-mm",
    "1",
    "--ae-mm",
    "2",
    "--mode",
    "down",
];

/// Seed 003's cutting coefficients as flags (N/mm², N/mm).
pub const SEED003_COEFFICIENTS: [&str; 12] = [
    "--ktc", "1889.2", "--krc", "806.1", "--kac", "291", "--kte", "63.12", "--kre", "113.7",
    "--kae", "-3.1",
];

/// Run `runout ARGS` with its reader gone at once (as with `| head -0`): it must end quietly —
/// status 0 or 141 (or killed by SIGPIPE), no panic, no "Broken pipe" message (issue 20 item 4).
pub fn closed_pipe<S: AsRef<std::ffi::OsStr> + std::fmt::Debug>(args: &[S]) {
    use std::process::{Command as StdCommand, Stdio};
    let mut child = StdCommand::new(assert_cmd::cargo::cargo_bin("runout"))
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    #[cfg(unix)]
    let killed_by_sigpipe = {
        use std::os::unix::process::ExitStatusExt;
        out.status.signal() == Some(13)
    };
    #[cfg(not(unix))]
    let killed_by_sigpipe = false;
    assert!(
        // 3 = finished with a "not identified" answer: when the whole report fits in the pipe's
        // buffer before the reader closes it, the write succeeds and the job's own status stands
        // (a race under load, seen with `displacement teeth` on 3 readings of 3 teeth)
        out.status.success() || killed_by_sigpipe || matches!(out.status.code(), Some(141 | 3)),
        "{args:?}: {:?} {err}",
        out.status
    );
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe"),
        "{args:?}: {err}"
    );
}

/// A JSON report as text without its `provenance` (the last field; command line, input names
/// and time differ between two runs that must otherwise agree). Text that has none is returned
/// as it is.
pub fn without_provenance(text: &str) -> String {
    match text.find(",\n  \"provenance\": {") {
        Some(i) => text[..i].to_string() + "\n}\n",
        None => text.to_string(),
    }
}

/// A plot file without its provenance metadata (SVG `<metadata id="runout-provenance">` element;
/// PNG `tEXt` chunk `runout-provenance`), for comparing the plots of two runs whose command lines
/// differ by design.
pub fn plot_without_provenance(path: &std::path::Path) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    if let Ok(text) = std::str::from_utf8(&bytes) {
        if let (Some(a), Some(b)) = (
            text.find("\n<metadata id=\"runout-provenance\">"),
            text.find("</metadata>"),
        ) {
            return [&text[..a], &text[b + "</metadata>".len()..]]
                .concat()
                .into_bytes();
        }
        return bytes;
    }
    // PNG: drop the tEXt chunk with the runout-provenance keyword
    let mut out = bytes[..8.min(bytes.len())].to_vec();
    let mut i = 8;
    while i + 12 <= bytes.len() {
        let n = u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
        let end = (i + 12 + n).min(bytes.len());
        let chunk = &bytes[i..end];
        if !(&chunk[4..8] == b"tEXt" && chunk[8..].starts_with(b"runout-provenance\0")) {
            out.extend_from_slice(chunk);
        }
        i = end;
    }
    out
}

/// Running a built `runout` command and checking how it ended (the `.output().unwrap()` +
/// `assert!(out.status.success())` boilerplate of the tests), with the other stream in the
/// failure message.
pub trait Ran {
    /// Run; assert it succeeded (its stderr in the message); its output.
    fn success_output(&mut self) -> std::process::Output;
    /// Run; assert it failed (its stdout in the message); its output.
    fn failure_output(&mut self) -> std::process::Output;
}

impl Ran for Command {
    fn success_output(&mut self) -> std::process::Output {
        let out = self.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    }

    fn failure_output(&mut self) -> std::process::Output {
        let out = self.output().unwrap();
        assert!(
            !out.status.success(),
            "succeeded: {}",
            String::from_utf8_lossy(&out.stdout)
        );
        out
    }
}

/// Time, Fx, Fy, Fz of a DynoWare example.
pub fn example_columns(name: &str) -> [Vec<f64>; 4] {
    let text = std::fs::read_to_string(example(&format!("identify/{name}"))).unwrap();
    let mut cols: [Vec<f64>; 4] = Default::default();
    for line in text.lines().skip_while(|l| !l.starts_with("Time,")).skip(2) {
        for (c, v) in cols.iter_mut().zip(line.split(',')) {
            c.push(v.parse().unwrap());
        }
    }
    cols
}

/// A minimal uncompressed MAT v5 writer (1×N double row vectors and scalars).
pub fn write_mat(path: &std::path::Path, vars: &[(&str, &[f64])]) {
    let mut b = Vec::new();
    let mut head = b"MATLAB 5.0 MAT-file, written by the runout test".to_vec();
    head.resize(116, b' ');
    b.extend_from_slice(&head);
    b.extend_from_slice(&[0; 8]);
    b.extend_from_slice(&0x0100u16.to_le_bytes());
    b.extend_from_slice(b"IM");
    let tag = |b: &mut Vec<u8>, ty: u32, n: usize| {
        b.extend_from_slice(&ty.to_le_bytes());
        b.extend_from_slice(&(n as u32).to_le_bytes());
    };
    for (name, v) in vars {
        let pad = name.len().div_ceil(8) * 8;
        let size = 16 + 16 + 8 + pad + 8 + v.len() * 8;
        tag(&mut b, 14, size);
        tag(&mut b, 6, 8);
        b.extend_from_slice(&6u32.to_le_bytes());
        b.extend_from_slice(&[0; 4]);
        tag(&mut b, 5, 8);
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(&(v.len() as i32).to_le_bytes());
        tag(&mut b, 1, name.len());
        b.extend_from_slice(name.as_bytes());
        b.resize(b.len() + pad - name.len(), 0);
        tag(&mut b, 9, v.len() * 8);
        for x in *v {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    std::fs::write(path, b).unwrap();
}

/// A minimal one-segment TDMS writer (f64 channels of group `group`, contiguous).
pub fn write_tdms(path: &std::path::Path, group: &str, chans: &[(&str, &[f64])]) {
    let mut meta = Vec::new();
    meta.extend_from_slice(&(chans.len() as u32).to_le_bytes());
    for (name, v) in chans {
        let p = format!("/'{group}'/'{name}'");
        meta.extend_from_slice(&(p.len() as u32).to_le_bytes());
        meta.extend_from_slice(p.as_bytes());
        meta.extend_from_slice(&20u32.to_le_bytes());
        meta.extend_from_slice(&10u32.to_le_bytes());
        meta.extend_from_slice(&1u32.to_le_bytes());
        meta.extend_from_slice(&(v.len() as u64).to_le_bytes());
        meta.extend_from_slice(&0u32.to_le_bytes());
    }
    let data: Vec<u8> = chans
        .iter()
        .flat_map(|(_, v)| v.iter().flat_map(|x| x.to_le_bytes()))
        .collect();
    let mut b = b"TDSm".to_vec();
    b.extend_from_slice(&(2u32 | 4 | 8).to_le_bytes());
    b.extend_from_slice(&4713u32.to_le_bytes());
    b.extend_from_slice(&((meta.len() + data.len()) as u64).to_le_bytes());
    b.extend_from_slice(&(meta.len() as u64).to_le_bytes());
    b.extend(meta);
    b.extend(data);
    std::fs::write(path, b).unwrap();
}
