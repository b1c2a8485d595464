//! Throughput of the shank-deflection force pipeline on a generated 4-channel 100 kHz CSV
//! (500 revolutions at 6000 rpm, ≈ 22 MB)
//! (issue 6 target ≥ 100 MB/s of input): both streaming passes (parse → survey; analyse; parse →
//! reconstruct → CSV output to a sink), against the parse-only pass measured in the same run.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use runout_core::shank::{
    analyse, OutputBlock, PairAxis, Reconstructor, SensorPair, ShankBeam, ShankSetup, Survey,
    SyntheticShank,
};
use runout_io::recording::{
    BinaryLayout, BinaryWriter, CsvWriter, ReadOptions, RecordingChunk, RecordingReader,
};
use std::f64::consts::TAU;
use std::hint::black_box;

const FS: f64 = 100_000.0;

/// Where output rows go (CSV or binary writer).
type RowSink = Box<dyn FnMut(&[f64])>;

fn generate() -> Vec<u8> {
    // a 3-tooth-like force: half-sine pulses per tooth period
    let per_rev = 720;
    let pulse = |i: usize, amp: f64| {
        let ph = (i as f64 / per_rev as f64 * 3.0).fract();
        if ph < 0.4 {
            amp * (ph / 0.4 * std::f64::consts::PI).sin()
        } else {
            0.0
        }
    };
    let fx: Vec<f64> = (0..per_rev)
        .map(|i| pulse(i, 80.0) * (TAU * i as f64 / per_rev as f64).cos())
        .collect();
    let fy: Vec<f64> = (0..per_rev).map(|i| -pulse(i, 200.0)).collect();
    let syn = SyntheticShank {
        beam: ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0).unwrap(),
        sample_rate_hz: FS,
        rpm: 6006.0,
        revolutions: (10.0, 480.0, 10.0),
        offset_mm: (0.008, 0.004),
        tilt: (0.0001, -0.0001),
        form_mm: (0.001, 0.0004),
        gap_mm: (0.5, 0.48),
        drift_mm: 0.0003,
        ramp_revolutions: 2.0,
        pulse: false,
        chain: Default::default(),
    };
    let mut k = 1u64;
    let rec = syn.generate(&fx, &fy, || {
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((k >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e-4
    });
    let mut s = String::from("time_s,xI_um,xII_um,yI_um,yII_um\n");
    for i in 0..rec.columns[0].len() {
        s += &format!(
            "{:.5},{:.4},{:.4},{:.4},{:.4}\n",
            i as f64 / FS,
            rec.columns[0][i] * 1e3,
            rec.columns[1][i] * 1e3,
            rec.columns[2][i] * 1e3,
            rec.columns[3][i] * 1e3
        );
    }
    s.into_bytes()
}

fn setup() -> ShankSetup {
    ShankSetup::new(
        ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0).unwrap(),
        vec![
            SensorPair {
                axis: PairAxis::X,
                sign: 1.0,
            },
            SensorPair {
                axis: PairAxis::Y,
                sign: 1.0,
            },
        ],
        FS,
        6000.0,
    )
}

fn to_mm(c: &mut RecordingChunk) {
    c.values
        .iter_mut()
        .for_each(|v| v.iter_mut().for_each(|x| *x *= 1e-3));
}

fn pipeline(bytes: &[u8], csv: bool) -> f64 {
    let opts = ReadOptions::new();
    let mut survey = Survey::new(&setup()).unwrap();
    let mut r = RecordingReader::from_bytes("bench.csv", bytes, &opts).unwrap();
    let mut c = RecordingChunk::default();
    while r.read_chunk(&mut c, 65_536).unwrap() > 0 {
        to_mm(&mut c);
        let cols: Vec<&[f64]> = c.values.iter().map(Vec::as_slice).collect();
        survey.push(&cols).unwrap();
    }
    let res = survey.finish().unwrap();
    let an = analyse(&res).unwrap();
    let mut rec = Reconstructor::new(&res, &an).unwrap();
    // the CLI's fixed decimals: time 1e-7 s, forces 0.1 mN, deflections 0.01 nm
    let names = rec.column_names();
    let mut w: RowSink = if csv {
        let mut w = CsvWriter::new(std::io::sink(), &names)
            .unwrap()
            .with_decimals(&[7, 4, 4, 5, 5, 5, 5, 0])
            .unwrap();
        Box::new(move |r: &[f64]| w.write_row(r).unwrap())
    } else {
        let mut w = BinaryWriter::new(
            std::io::sink(),
            &names,
            BinaryLayout::F32,
            serde_json::Value::Null,
        )
        .unwrap();
        Box::new(move |r: &[f64]| w.write_row(r).unwrap())
    };
    let mut out = OutputBlock::default();
    let mut r = RecordingReader::from_bytes("bench.csv", bytes, &opts).unwrap();
    let mut acc = 0.0;
    let mut row = [0.0; 8];
    while r.read_chunk(&mut c, 65_536).unwrap() > 0 {
        to_mm(&mut c);
        let cols: Vec<&[f64]> = c.values.iter().map(Vec::as_slice).collect();
        rec.push(&cols, &mut out).unwrap();
        for i in 0..out.len() {
            row = [
                out.time_s[i],
                out.force_n[0][i],
                out.force_n[1][i],
                out.delta_i_um[0][i],
                out.delta_ii_um[0][i],
                out.delta_i_um[1][i],
                out.delta_ii_um[1][i],
                f64::from(u8::from(out.saturated[i])),
            ];
            w(&row);
        }
        acc += out.force_n[1].iter().sum::<f64>();
    }
    acc + row[0]
}

fn parse_only(bytes: &[u8]) -> f64 {
    let mut r = RecordingReader::from_bytes("bench.csv", bytes, &ReadOptions::new()).unwrap();
    let mut c = RecordingChunk::default();
    let mut acc = 0.0;
    while r.read_chunk(&mut c, 65_536).unwrap() > 0 {
        acc += c.values[0][0];
    }
    acc
}

fn bench(c: &mut Criterion) {
    let bytes = generate();
    let mut g = c.benchmark_group("shank_4ch_100kHz_csv");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.sample_size(10);
    g.bench_function("parse_only_one_pass", |b| {
        b.iter(|| black_box(parse_only(black_box(&bytes))))
    });
    g.bench_function("force_pipeline_two_passes_with_csv_output", |b| {
        b.iter(|| black_box(pipeline(black_box(&bytes), true)))
    });
    g.bench_function("force_pipeline_two_passes_with_f32_binary_output", |b| {
        b.iter(|| black_box(pipeline(black_box(&bytes), false)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
