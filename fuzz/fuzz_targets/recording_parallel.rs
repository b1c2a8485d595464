//! Differential: a text recording's rows parsed in jobs on two threads
//! (`RecordingReader::for_each_chunk_in_jobs_of`, the common-row path and its hand-back)
//! against `read_chunk` in a loop, on 1100 well-formed rows followed by the fuzzer's bytes as
//! more lines (the parallel path starts after the 1000 rows read ahead at open). Chunks (sizes,
//! first samples, times and values bit for bit), the first error, the bytes read and the
//! warnings must be the same. On Linux the same bytes are also written to a file and parsed
//! mapped (`runout_io::mapped`), with the same result required.
//!
//! Run with `-detect_leaks=0`: LeakSanitizer reports the standard library's per-thread channel
//! context (`std::sync::mpmc::context`, ≈ 112 bytes) of a worker thread that is still exiting
//! when the check runs; no allocation of ours is involved.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::recording::{ReadOptions, RecordingChunk, RecordingReader};

type Seen = (
    Vec<(u64, Vec<u64>, Vec<Vec<u64>>)>,
    Option<String>,
    u64,
    Vec<String>,
);

fn bits(c: &RecordingChunk) -> (u64, Vec<u64>, Vec<Vec<u64>>) {
    (
        c.first_sample,
        c.time_s.iter().map(|t| t.to_bits()).collect(),
        c.values
            .iter()
            .map(|v| v.iter().map(|x| x.to_bits()).collect())
            .collect(),
    )
}

/// What `for_each_chunk_in_jobs_of` gives on 2 threads, with the reader's name `name` in
/// messages written as `f.csv`.
fn in_jobs<R: std::io::BufRead + Send>(
    mut r: RecordingReader<R>,
    job_bytes: usize,
    name: &str,
) -> Seen {
    let mut c = RecordingChunk::default();
    let mut chunks = Vec::new();
    let error = r
        .for_each_chunk_in_jobs_of(job_bytes, &mut c, 333, 2, |c, _, _| {
            chunks.push(bits(c));
            true
        })
        .err()
        .map(|e| e.to_string().replace(name, "f.csv"));
    let warnings = r
        .warnings()
        .iter()
        .map(|w| w.replace(name, "f.csv"))
        .collect();
    (chunks, error, r.bytes_read(), warnings)
}

fuzz_target!(|data: &[u8]| {
    let Some((&knobs, tail)) = data.split_first() else {
        return;
    };
    let delim = [b',', b';', b'\t'][usize::from(knobs % 3)];
    let crlf = knobs & 4 != 0;
    let job_bytes = 16 + usize::from(knobs >> 3) * 37;
    let d = delim as char;
    let end = if crlf { "\r\n" } else { "\n" };
    let mut text = format!("time_s{d}a_N{d}b_N{end}");
    for k in 0..1100u32 {
        let a = if delim == b';' && knobs & 64 != 0 {
            format!("{:.3}", f64::from(k) * 0.7 - 300.0).replace('.', ",")
        } else {
            format!("{:.3}", f64::from(k) * 0.7 - 300.0)
        };
        text += &format!("{:.4}{d}{a}{d}-{}.25{end}", f64::from(k) / 1e4, k % 7);
    }
    let mut bytes = text.into_bytes();
    bytes.extend_from_slice(tail);
    let opts = ReadOptions::new();
    let Ok(mut serial) = RecordingReader::from_bytes("f.csv", &bytes, &opts) else {
        return;
    };
    let mut c = RecordingChunk::default();
    let mut want: Seen = (Vec::new(), None, 0, Vec::new());
    want.1 = loop {
        match serial.read_chunk(&mut c, 333) {
            Ok(0) => break None,
            Ok(_) => want.0.push(bits(&c)),
            Err(e) => break Some(e.to_string()),
        }
    };
    want.2 = serial.bytes_read();
    want.3 = serial.warnings().to_vec();
    let parallel = RecordingReader::from_bytes("f.csv", &bytes, &opts).expect("opened once");
    let got = in_jobs(parallel, job_bytes, "f.csv");
    assert!(
        got == want,
        "{:?}\n{:?}\n{} {}",
        got.1,
        want.1,
        got.2,
        want.2
    );
    #[cfg(target_os = "linux")]
    {
        // the file's path in messages is the only difference allowed
        let path = std::env::temp_dir().join(format!("fuzz-mapped-{}.csv", std::process::id()));
        std::fs::write(&path, &bytes).expect("temporary file");
        // SAFETY: the file is not written while it is read
        unsafe { runout_io::mapped::allow_mapped_files() };
        let mapped = RecordingReader::open(&path, &opts).expect("opened before");
        let got = in_jobs(mapped, job_bytes, &path.display().to_string());
        assert!(
            got == want,
            "mapped: {:?}\n{:?}\n{} {}",
            got.1,
            want.1,
            got.2,
            want.2
        );
    }
});
