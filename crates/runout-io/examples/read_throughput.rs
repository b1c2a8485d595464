//! Parse a CSV recording with the runout reader or with the `csv` crate + `str::parse` (the
//! baseline of `benches/read.rs`), for CPU-time comparisons on large files under
//! `/usr/bin/time -v` when the machine is too busy for stable wall-clock benchmarks:
//!
//! `cargo run --release -p runout-io --example read_throughput -- FILE.csv runout|csv`

use runout_io::recording::{ReadOptions, RecordingChunk, RecordingReader};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (path, mode) = (
        args.get(1)
            .ok_or("usage: read_throughput FILE.csv runout|csv")?,
        args.get(2).map_or("runout", String::as_str),
    );
    let t = std::time::Instant::now();
    let (rows, sum) = match mode {
        "runout" => {
            let mut r = RecordingReader::open(path, &ReadOptions::new())?;
            let mut c = RecordingChunk::default();
            let (mut rows, mut sum) = (0usize, 0.0);
            while r.read_chunk(&mut c, 65_536)? > 0 {
                rows += c.len();
                sum += c.values.iter().map(|v| v.iter().sum::<f64>()).sum::<f64>();
            }
            (rows, sum)
        }
        "csv" => {
            let mut r = csv::ReaderBuilder::new().from_path(path)?;
            let mut rec = csv::ByteRecord::new();
            let ncol = r.byte_headers()?.len();
            let mut cols: Vec<Vec<f64>> = vec![Vec::with_capacity(65_536); ncol];
            let (mut rows, mut sum) = (0usize, 0.0);
            while r.read_byte_record(&mut rec)? {
                for (c, f) in cols.iter_mut().zip(rec.iter()) {
                    c.push(std::str::from_utf8(f)?.parse::<f64>()?);
                }
                rows += 1;
                if cols[0].len() == 65_536 {
                    sum += cols[1..].iter().map(|v| v.iter().sum::<f64>()).sum::<f64>();
                    cols.iter_mut().for_each(Vec::clear);
                }
            }
            (
                rows,
                sum + cols[1..].iter().map(|v| v.iter().sum::<f64>()).sum::<f64>(),
            )
        }
        other => return Err(format!("mode `{other}`: expected runout or csv").into()),
    };
    let secs = t.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(path)?.len() as f64;
    println!(
        "{mode}: {rows} rows, checksum {sum:.6e}, {secs:.3} s wall, {:.1} MB/s wall",
        bytes / secs / 1e6
    );
    Ok(())
}
