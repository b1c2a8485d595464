//! Parse throughput of the recording reader on a generated multi-channel CSV (issue 3 target:
//! ≥ 100 MB/s), against two baselines in the same run: the `csv` crate's `ByteRecord` reader with
//! `str::parse::<f64>` per cell (what a straightforward implementation would do), and the reader's
//! own line path before issue 18 (each line copied out of a `BufReader` by `read_until`, split,
//! cells parsed by the same float parser; kept here as `old_line_copy_path`). `runout_reader_2_threads`
//! is the same reader with the data rows parsed on two threads (`for_each_chunk`, issue 18).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use runout_io::recording::{ReadOptions, RecordingChunk, RecordingReader};
use std::hint::black_box;

/// A 50 kHz recording: time + 4 force-like channels with 4–6 significant digits, in fixed
/// notation or (`scientific`) in scientific notation (`1.5034e2`) as some acquisition programs
/// export it — then every cell takes the parser's exponent path.
fn generate(rows: usize, scientific: bool) -> Vec<u8> {
    let mut s = String::from("time_s,fx_N,fy_N,fz_N,mz_Nm\n");
    for k in 0..rows {
        let t = k as f64 / 50_000.0;
        let a = (t * 1083.0).sin();
        let (fx, fy, fz, mz) = (
            150.0 * a,
            -80.0 * (t * 2166.0).cos(),
            12.5 * a * a,
            0.35 * a,
        );
        s += &if scientific {
            format!("{t:.5e},{fx:.4e},{fy:.4e},{fz:.4e},{mz:.4e}\n")
        } else {
            format!("{t:.5},{fx:.3},{fy:.3},{fz:.3},{mz:.4}\n")
        };
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

/// The same reader with its data rows parsed on two threads (`for_each_chunk`, issue 18).
fn read_all_ours_2_threads(bytes: &[u8]) -> f64 {
    let mut r = RecordingReader::from_bytes("bench.csv", bytes, &ReadOptions::new()).unwrap();
    let mut c = RecordingChunk::default();
    let mut sum = 0.0;
    r.for_each_chunk(&mut c, 65_536, 2, |c, _, _| {
        sum += c.values[0].iter().sum::<f64>();
        true
    })
    .unwrap();
    sum
}

/// The data loop of the reader before issue 18, reduced to its work: `read_until` copies each
/// line out of the `BufReader` (64 KiB), the line is split on the delimiter and every cell parsed
/// with the reader's float parser (the copy below, `old_parse_number`), into 65 536-row chunks.
fn read_all_old_line_copy_path(bytes: &[u8]) -> f64 {
    use std::io::{BufRead, Read};
    let mut src = std::io::BufReader::with_capacity(1 << 16, bytes);
    let mut buf = Vec::new();
    src.read_until(b'\n', &mut buf).unwrap(); // header
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 5];
    let mut sum = 0.0;
    loop {
        buf.clear();
        let n = (&mut src)
            .take(1 << 20)
            .read_until(b'\n', &mut buf)
            .unwrap();
        if n == 0 {
            break;
        }
        if buf.last() == Some(&b'\n') {
            buf.pop();
        }
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
        if buf.is_empty() {
            continue;
        }
        for (c, f) in cols.iter_mut().zip(buf.split(|&c| c == b',')) {
            c.push(old_parse_number(f, false).unwrap());
        }
        if cols[0].len() == 65_536 {
            sum += cols[1].iter().sum::<f64>();
            cols.iter_mut().for_each(Vec::clear);
        }
    }
    sum + cols[1].iter().sum::<f64>()
}

/// The reader's float parser before issue 18 (`recording/text.rs`, Clinger's fast path, else
/// `str::parse`), copied as the baseline.
fn old_parse_number(cell: &[u8], decimal_comma: bool) -> Option<f64> {
    const POW10: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
        1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    let mut b = cell;
    while let [first, rest @ ..] = b {
        if *first == b' ' || *first == b'\t' {
            b = rest;
        } else {
            break;
        }
    }
    while let [rest @ .., last] = b {
        if *last == b' ' || *last == b'\t' || *last == b'\r' {
            b = rest;
        } else {
            break;
        }
    }
    if b.len() >= 2 && b[0] == b'"' && b[b.len() - 1] == b'"' {
        b = &b[1..b.len() - 1];
    }
    let n = b.len();
    let (neg, mut i) = match b.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    let mut mant: u64 = 0;
    let int_start = i;
    while i < n {
        let d = b[i].wrapping_sub(b'0');
        if d >= 10 {
            break;
        }
        mant = mant.wrapping_mul(10).wrapping_add(u64::from(d));
        i += 1;
    }
    let int_digits = i - int_start;
    let mut frac_digits = 0;
    if i < n && (b[i] == b'.' || (decimal_comma && b[i] == b',')) {
        i += 1;
        let frac_start = i;
        while i < n {
            let d = b[i].wrapping_sub(b'0');
            if d >= 10 {
                break;
            }
            mant = mant.wrapping_mul(10).wrapping_add(u64::from(d));
            i += 1;
        }
        frac_digits = i - frac_start;
    }
    if int_digits + frac_digits == 0 || i < n || int_digits + frac_digits > 19 {
        // exponents, long mantissas: not in this benchmark's data (the std fallback)
        return std::str::from_utf8(b).ok()?.parse().ok();
    }
    let exp10 = -(frac_digits as i64);
    let v = if mant == 0 {
        0.0
    } else if mant < (1u64 << 53) && exp10 >= -22 {
        mant as f64 / POW10[(-exp10) as usize]
    } else {
        return std::str::from_utf8(b).ok()?.parse().ok();
    };
    Some(if neg { -v } else { v })
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
    let bytes = generate(400_000, false);
    assert_eq!(read_all_ours(&bytes), read_all_csv_crate(&bytes));
    assert_eq!(read_all_ours(&bytes), read_all_old_line_copy_path(&bytes));
    assert_eq!(read_all_ours(&bytes), read_all_ours_2_threads(&bytes));
    let mut g = c.benchmark_group("parse_csv_5col");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.sample_size(10);
    g.bench_function("runout_reader", |b| {
        b.iter(|| black_box(read_all_ours(black_box(&bytes))))
    });
    g.bench_function("runout_reader_2_threads", |b| {
        b.iter(|| black_box(read_all_ours_2_threads(black_box(&bytes))))
    });
    g.bench_function("old_line_copy_path", |b| {
        b.iter(|| black_box(read_all_old_line_copy_path(black_box(&bytes))))
    });
    g.bench_function("csv_crate_str_parse", |b| {
        b.iter(|| black_box(read_all_csv_crate(black_box(&bytes))))
    });
    g.finish();
    let sci = generate(400_000, true);
    assert_eq!(read_all_ours(&sci), read_all_csv_crate(&sci));
    let mut g = c.benchmark_group("parse_csv_5col_scientific");
    g.throughput(Throughput::Bytes(sci.len() as u64));
    g.sample_size(10);
    g.bench_function("runout_reader", |b| {
        b.iter(|| black_box(read_all_ours(black_box(&sci))))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
