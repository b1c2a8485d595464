//! Parse throughput of the recording reader on a generated multi-channel CSV (issue 3 target:
//! ≥ 100 MB/s), against a baseline in the same run: the `csv` crate's `ByteRecord` reader with
//! `str::parse::<f64>` per cell (what a straightforward implementation would do).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use runout_io::recording::{ReadOptions, RecordingChunk, RecordingReader};
use std::hint::black_box;

/// A 50 kHz recording: time + 4 force-like channels with 4–6 significant digits.
fn generate(rows: usize) -> Vec<u8> {
    let mut s = String::from("time_s,fx_N,fy_N,fz_N,mz_Nm\n");
    for k in 0..rows {
        let t = k as f64 / 50_000.0;
        let a = (t * 1083.0).sin();
        s += &format!(
            "{t:.5},{:.3},{:.3},{:.3},{:.4}\n",
            150.0 * a,
            -80.0 * (t * 2166.0).cos(),
            12.5 * a * a,
            0.35 * a
        );
    }
    s.into_bytes()
}

fn read_all_ours(bytes: &[u8]) -> f64 {
    let mut r = RecordingReader::from_bytes("bench.csv", bytes, &ReadOptions::new()).unwrap();
    let mut c = RecordingChunk::default();
    let mut sum = 0.0;
    while r.read_chunk(&mut c, 65_536).unwrap() > 0 {
        sum += c.values[0].iter().sum::<f64>();
    }
    sum
}

fn read_all_csv_crate(bytes: &[u8]) -> f64 {
    let mut r = csv::ReaderBuilder::new().from_reader(bytes);
    let mut rec = csv::ByteRecord::new();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 5];
    let mut sum = 0.0;
    while r.read_byte_record(&mut rec).unwrap() {
        for (c, f) in cols.iter_mut().zip(rec.iter()) {
            c.push(std::str::from_utf8(f).unwrap().parse::<f64>().unwrap());
        }
        if cols[0].len() == 65_536 {
            sum += cols[1].iter().sum::<f64>();
            cols.iter_mut().for_each(Vec::clear);
        }
    }
    sum + cols[1].iter().sum::<f64>()
}

fn bench(c: &mut Criterion) {
    let bytes = generate(400_000);
    assert_eq!(read_all_ours(&bytes), read_all_csv_crate(&bytes));
    let mut g = c.benchmark_group("parse_csv_5col");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.sample_size(10);
    g.bench_function("runout_reader", |b| {
        b.iter(|| black_box(read_all_ours(black_box(&bytes))))
    });
    g.bench_function("csv_crate_str_parse", |b| {
        b.iter(|| black_box(read_all_csv_crate(black_box(&bytes))))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
