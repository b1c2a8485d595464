//! Read throughput per recording format (issue 16), against the CSV reader in the same run: one
//! recording of 1 000 000 samples × (time, Fx, Fy, Fz) written as CSV, MAT v5 (plain and
//! compressed), TDMS, HDF5 and Parquet by `tests/fixtures/make_fixtures.py --bench` (needs
//! python3 with scipy, h5py, nptdms, pyarrow; formats whose file is missing are skipped with a
//! message). Each benchmark opens the file through `open_recording` and reads every chunk;
//! criterion's throughput is bytes of the file (MB/s); rows/s = 1e6 / time (4 samples a row).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use runout_io::recording::{open_recording, ReadOptions, RecordingChunk};
use std::hint::black_box;
use std::path::{Path, PathBuf};

const SAMPLES: usize = 1_000_000;

fn files() -> Option<PathBuf> {
    let dir = std::env::temp_dir().join(format!("runout-bench-formats-{SAMPLES}"));
    if dir.join("bench.parquet").exists() {
        return Some(dir);
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/make_fixtures.py");
    let ok = std::process::Command::new("python3")
        .arg(script)
        .arg(&dir)
        .args(["--bench", &SAMPLES.to_string()])
        .status()
        .is_ok_and(|s| s.success());
    ok.then_some(dir)
}

fn read_all(path: &Path) -> f64 {
    let mut r = open_recording(path, &ReadOptions::new().channels(&["Fx", "Fy", "Fz"])).unwrap();
    let mut c = RecordingChunk::default();
    let mut sum = 0.0;
    while r.read_chunk(&mut c, 65_536).unwrap() > 0 {
        sum += c.values[0].iter().sum::<f64>() + c.time_s[c.len() - 1];
    }
    sum
}

fn bench(c: &mut Criterion) {
    let Some(dir) = files() else {
        eprintln!("formats bench: python3 with scipy, h5py, nptdms, pyarrow is needed to write the files; skipped");
        return;
    };
    let mut g = c.benchmark_group("formats");
    g.sample_size(10)
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(4));
    for f in [
        "bench.csv",
        "bench.mat",
        "bench_z.mat",
        "bench.tdms",
        "bench.h5",
        "bench.parquet",
    ] {
        let p = dir.join(f);
        let bytes = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        g.throughput(Throughput::Bytes(bytes));
        g.bench_function(f, |b| b.iter(|| black_box(read_all(&p))));
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
