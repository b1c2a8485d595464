//! Binary recording formats (issue 16): fixtures written by independent writers (scipy, h5py,
//! nptdms, pyarrow; `tests/fixtures/make_fixtures.py`) read back exactly, values and time base,
//! through the one entry point `open_recording`; clear errors for missing names.

use runout_io::formats::{detect, inspect, Kind};
use runout_io::recording::{open_recording, Format, ReadOptions, RecordingChunk, RecordingError};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// Read every case of `expected.json` from `dir`; returns the number of cases checked.
fn check_dir(dir: &Path) -> usize {
    let text = std::fs::read_to_string(dir.join("expected.json")).unwrap();
    let cases: serde_json::Map<String, Value> = serde_json::from_str(&text).unwrap();
    let mut checked = 0;
    for (key, case) in &cases {
        let file = case["file"].as_str().unwrap();
        let mut spec = dir.join(file).display().to_string();
        if let Some(sel) = case["selector"].as_str() {
            spec += &format!(":{sel}");
        }
        let channels: Vec<(&String, Vec<f64>)> = case["channels"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(k, v)| {
                (
                    k,
                    v.as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap())
                        .collect(),
                )
            })
            .collect();
        let names: Vec<&str> = channels.iter().map(|(k, _)| k.as_str()).collect();
        let mut opts = ReadOptions::new().channels(&names).chunk_rows(37);
        if let Some(t) = case["time_var"].as_str() {
            opts = opts.time_column(t);
        }
        let mut r = open_recording(&spec, &opts).unwrap_or_else(|e| panic!("{key}: {e}"));
        let fs = case["sample_rate_hz"].as_f64().unwrap();
        let t0 = case["start_time_s"].as_f64().unwrap();
        let info = r.info().clone();
        assert!(
            ((info.sample_rate_hz - fs) / fs).abs() < 1e-9,
            "{key}: rate {} vs {fs} ({})",
            info.sample_rate_hz,
            info.sample_rate_source
        );
        assert_eq!(info.start_time_s, t0, "{key}");
        assert_eq!(info.channels.len(), channels.len(), "{key}");
        let mut got: Vec<Vec<f64>> = vec![Vec::new(); channels.len()];
        let mut times = Vec::new();
        let mut c = RecordingChunk::default();
        let mut chunks = 0;
        while r
            .read_chunk(&mut c, 37)
            .unwrap_or_else(|e| panic!("{key}: {e}"))
            > 0
        {
            chunks += 1;
            times.extend_from_slice(&c.time_s);
            for (g, v) in got.iter_mut().zip(&c.values) {
                g.extend_from_slice(v);
            }
        }
        assert!(chunks > 1, "{key}: read in several chunks");
        for ((name, want), g) in channels.iter().zip(&got) {
            assert_eq!(g, want, "{key}: channel {name}");
        }
        let n = got[0].len();
        let expected_t: Vec<f64> = (0..n).map(|k| t0 + k as f64 / fs).collect();
        if case["time_var"].is_null() {
            assert_eq!(times, expected_t, "{key}: time base");
        } else {
            for (a, b) in times.iter().zip(&expected_t) {
                assert!((a - b).abs() < 1e-12, "{key}: time {a} vs {b}");
            }
        }
        checked += 1;
    }
    checked
}

#[test]
fn committed_fixtures_read_back_exactly() {
    let n = check_dir(&fixtures());
    assert!(n >= 15, "only {n} cases");
}

#[test]
#[ignore = "needs python3 with scipy, h5py, nptdms, pyarrow: .ci/run installs them"]
fn fixtures_made_now_by_independent_writers_read_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let st = std::process::Command::new("python3")
        .arg(fixtures().join("make_fixtures.py"))
        .arg(dir.path())
        .status()
        .expect("python3");
    assert!(st.success());
    assert!(check_dir(dir.path()) >= 15);
}

#[test]
fn detection_by_content_not_extension() {
    for (f, want) in [
        ("mat5_plain.mat", Kind::Mat5),
        ("mat5_compressed.mat", Kind::Mat5),
        ("mat73.mat", Kind::Hdf5 { offset: 512 }),
        ("plain.h5", Kind::Hdf5 { offset: 0 }),
        ("tdms_big_endian.tdms", Kind::Tdms),
        ("table.parquet", Kind::Parquet),
    ] {
        let bytes = std::fs::read(fixtures().join(f)).unwrap();
        assert_eq!(detect(&bytes), want, "{f}");
    }
    // a renamed file is still read by content
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("recording.txt");
    std::fs::copy(fixtures().join("tdms_interleaved.tdms"), &p).unwrap();
    let r = open_recording(&p, &ReadOptions::new()).unwrap();
    assert!(matches!(r.info().format, Format::Tdms { version: 4713 }));
    assert_eq!(detect(b"Time,Fx\n0,1\n"), Kind::Text);
}

#[test]
fn missing_variable_is_named_and_the_contents_listed() {
    let p = fixtures().join("mat5_plain.mat");
    let e = open_recording(
        format!("{}:600", p.display()),
        &ReadOptions::new().channels(&["Fq"]),
    )
    .err()
    .unwrap();
    let m = e.to_string();
    assert!(matches!(e, RecordingError::MissingChannel { .. }), "{m}");
    assert!(m.contains("mat5_plain.mat") && m.contains("`Fq`"), "{m}");
    assert!(
        m.contains("Fx_600 (200 × f64)") && m.contains("comment"),
        "{m}"
    );
    // an unknown selector
    let e = open_recording(format!("{}:700", p.display()), &ReadOptions::new())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("selector `700`") && e.contains("Fy_800"), "{e}");
    // TDMS channel
    let e = open_recording(
        fixtures().join("tdms_daqmx.tdms"),
        &ReadOptions::new().channels(&["Group/Fz"]),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("`Group/Fz`") && e.contains("Group/Fx (200 × DAQmx i16 (scaled)"),
        "{e}"
    );
    // HDF5 dataset
    let e = open_recording(
        fixtures().join("plain.h5"),
        &ReadOptions::new().channels(&["/force/Fw"]),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("/force/Fw") && e.contains("/force/Fx (200 × f64, N)"),
        "{e}"
    );
}

#[test]
fn no_sample_rate_is_a_clear_error_and_the_caller_rate_wins() {
    let bytes = std::fs::read(fixtures().join("tdms_incremental.tdms")).unwrap();
    let r = runout_io::recording::recording_from_bytes(
        "x.tdms",
        &bytes,
        None,
        &ReadOptions::new().channels(&["Fx"]).sample_rate_hz(50.0),
    )
    .unwrap();
    assert_eq!(r.info().sample_rate_hz, 50.0);
    assert_eq!(r.info().sample_rate_source, "given by the caller");
    // a MAT file without rate variable or time vector
    let dir = tempfile::tempdir().unwrap();
    let q = dir.path().join("norate.mat");
    let mut b = std::fs::read(fixtures().join("mat5_plain.mat")).unwrap();
    // rename the variable `fs` → `fq` in place (names are stored as text)
    let pos = b.windows(4).position(|w| w == b"fs\0\0").unwrap();
    b[pos + 1] = b'q';
    std::fs::write(&q, &b).unwrap();
    let e = open_recording(format!("{}:600", q.display()), &ReadOptions::new())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("no sample rate") && e.contains("fq"), "{e}");
}

#[test]
fn inspect_lists_channels_lengths_rates() {
    let c = inspect(&fixtures().join("tdms_writer.tdms"), &ReadOptions::new()).unwrap();
    let fx = c.entries.iter().find(|e| e.name == "Force/Fx").unwrap();
    assert_eq!(fx.len, 200);
    assert_eq!(fx.unit.as_deref(), Some("N"));
    assert_eq!(fx.sample_rate_hz, Some(1000.0));
    assert_eq!(fx.start_time_s, Some(0.25));
    let c = inspect(&fixtures().join("mat5_struct.mat"), &ReadOptions::new()).unwrap();
    assert!(c
        .entries
        .iter()
        .any(|e| e.name == "rec800.Fy" && e.len == 200));
    assert!(c.entries.iter().any(|e| e.name == "note" && !e.readable));
}

/// A FIFO at `dir/name` whose writer thread writes `bytes` once a reader opens it.
#[cfg(target_os = "linux")]
fn fifo_with(dir: &Path, name: &str, bytes: Vec<u8>) -> (PathBuf, std::thread::JoinHandle<()>) {
    use std::io::Write;
    let p = dir.join(name);
    let c = std::ffi::CString::new(p.display().to_string()).unwrap();
    // SAFETY: a NUL-terminated path; mkfifo only creates the node
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let q = p.clone();
    let writer = std::thread::spawn(move || {
        // blocks until the reader opens; a reader that stops early breaks the pipe (ignored)
        let mut f = std::fs::OpenOptions::new().write(true).open(q).unwrap();
        let _ = f.write_all(&bytes);
    });
    (p, writer)
}

/// `f()` on a thread, against a deadline of a minute: a second open of a FIFO would wait for a
/// writer forever (the old reader opened a recording twice).
fn within_a_minute<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(f()).ok());
    rx.recv_timeout(std::time::Duration::from_secs(60))
        .expect("the pipe is opened and read within a minute")
}

/// All of a reader's rows: the time base and each channel.
fn read_all_rows<R: std::io::BufRead>(
    r: &mut runout_io::recording::RecordingReader<R>,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let (mut times, mut values) = (Vec::new(), Vec::new());
    let mut c = RecordingChunk::default();
    while r.read_chunk(&mut c, 1000).unwrap() > 0 {
        times.extend_from_slice(&c.time_s);
        values.resize(c.values.len(), Vec::new());
        for (g, v) in values.iter_mut().zip(&c.values) {
            g.extend_from_slice(v);
        }
    }
    (times, values)
}

/// A text recording from a pipe (`<(zcat rec.txt.gz)`, standard input, a FIFO) is opened once
/// and read from its first byte: the same header, rate and rows as from a file. (It was opened
/// twice — once to detect the format, once to read — and the second reader started after the
/// bytes the first had taken: "no sample rate" or "no column Fx" for a DynoWare export.)
#[cfg(target_os = "linux")]
#[test]
fn a_text_recording_is_read_from_a_pipe_as_from_a_file() {
    let mut text = String::from(
        "DynoWare,Version 2.5.1.2\nSampling rate [Hz]:,2000\nTime,Fx,Fy,Fz\ns,N,N,N\n",
    );
    for k in 0..20_000 {
        let t = k as f64 / 2000.0;
        let line = format!("{t},{:.4},{:.4},{:.4}\n", (7.0 * t).sin(), -t, 0.5 * t);
        text.push_str(&line);
    }
    assert!(text.len() > 4 << 16, "longer than a pipe's buffer");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("rec.txt");
    std::fs::write(&file, &text).unwrap();
    let opts = ReadOptions::new().channels(&["Fx", "Fy", "Fz"]);
    let mut from_file = open_recording(&file, &opts).unwrap();
    let want = read_all_rows(&mut from_file);
    assert_eq!(want.0.len(), 20_000);
    let (fifo, writer) = fifo_with(dir.path(), "rec.fifo", text.into_bytes());
    let source = from_file.info().sample_rate_source.clone();
    let (info, got) = within_a_minute(move || {
        let mut r = open_recording(&fifo, &opts).unwrap();
        (r.info().clone(), read_all_rows(&mut r))
    });
    assert_eq!(info.sample_rate_hz, 2000.0);
    assert_eq!(info.sample_rate_source, source);
    assert_eq!(got, want);
    writer.join().unwrap();
    // `inspect` (`runout inspect <(cat rec.txt)`) lists what the pipe holds
    let (fifo, writer) = fifo_with(dir.path(), "rec2.fifo", std::fs::read(&file).unwrap());
    let catalog = within_a_minute(move || inspect(&fifo, &ReadOptions::new()).unwrap());
    let names: Vec<&str> = catalog.entries.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(names, ["Time", "Fx", "Fy", "Fz"]);
    assert_eq!(catalog.entries[1].sample_rate_hz, Some(2000.0));
    writer.join().unwrap(); // (the inspection reads the head only: the writer meets a closed pipe)
}

/// A binary format needs to seek: from a pipe it is a clear error naming the file and the
/// format, not a misread.
#[cfg(target_os = "linux")]
#[test]
fn a_binary_recording_from_a_pipe_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(fixtures().join("tdms_interleaved.tdms")).unwrap();
    let (fifo, writer) = fifo_with(dir.path(), "rec.fifo", bytes);
    let e = within_a_minute(move || open_recording(&fifo, &ReadOptions::new()).err())
        .expect("a TDMS file from a pipe is an error");
    let msg = e.to_string();
    assert!(matches!(e, RecordingError::Format { .. }), "{msg}");
    assert!(
        msg.contains("rec.fifo") && msg.contains("TDMS") && msg.contains("pipe"),
        "{msg}"
    );
    writer.join().unwrap();
}
