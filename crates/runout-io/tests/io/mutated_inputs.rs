//! Stable-toolchain counterpart of the fuzz targets (issue 14, README "Fuzzing"): every parser of
//! `runout-io` is fed mutated bytes of its example files (bit flips, inserted and deleted bytes,
//! truncation, a splice of two examples, a duplicated line). Each one must return without
//! panicking, and either `Ok` or an error that names the file (or the parameter) and, when it
//! gives a line, a line that exists. Fuzz crashers found so far are at the end
//! (`fuzz_regressions`).

use proptest::prelude::*;
use runout_io::config::chip::{parse_case_specs, resolve_case};
use runout_io::config::identify::{identify_key_names, resolve_identify};
use runout_io::config::shank::ShankConfig;
use runout_io::config::simulate::{resolve_simulate, simulate_key_names};
use runout_io::config::{layer_from_toml, Settings};
use runout_io::displacement::{read_height_table, read_signal, read_tooth_table, SignalSection};
use runout_io::frf::parse_frf;
use runout_io::gcode::{lex, NcProgram, RewriteOptions};
use runout_io::grind::{read_edge_csv, read_probe_csv};
use runout_io::peak_table;
use runout_io::recording::{AxisMapping, ReadOptions, Recording};
use runout_io::toolpath::{joint_points, parse_apt, parse_cl_csv, parse_joint_csv};
use runout_io::units::{parse_quantity, Quantity};

/// An example file of the repository (the fuzz seeds are copies of `examples/` and test data,
/// plus the displacement and FRF tables that have no example of their own).
macro_rules! seed {
    ($path:literal) => {
        include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../", $path)) as &[u8]
    };
}

const RECORDINGS: &[&[u8]] = &[
    seed!("fuzz/seeds/recording/rec.csv"),
    seed!("fuzz/seeds/recording/semicolon.csv"),
    seed!("fuzz/seeds/recording/dynoware.txt"),
    seed!("crates/runout-cli/tests/data/issue20/shank_recording.csv"),
];
const AXES: &[&[u8]] = &[
    seed!("fuzz/seeds/recording/axes"),
    b"x = Fx, y = -Fy",
    b"x=-Fy;y=-Fx;z=-Fz",
];
const QUANTITIES: &[&[u8]] = &[
    seed!("fuzz/seeds/units_config/q"),
    b"10 mm",
    b"0.25in",
    b"-30 deg",
    b"1.5e3 rpm",
    b"2 ms",
    b"8 \xc2\xb5m",
];
const CONFIGS: &[&[u8]] = &[
    seed!("examples/simulate.toml"),
    seed!("examples/identify/cut.toml"),
];
const SHANK_CONFIGS: &[&[u8]] = &[
    seed!("crates/runout-cli/tests/data/shank.toml"),
    seed!("crates/runout-cli/tests/data/issue20/shank_reversed_air_cut.toml"),
];
const CHIP_CASES: &[&[u8]] = &[
    seed!("fuzz/seeds/chip_case/section2_5.toml"),
    seed!("fuzz/seeds/chip_case/flank_path"),
    seed!("fuzz/seeds/chip_case/joints"),
];
const TOOLPATHS: &[&[u8]] = &[
    seed!("examples/chip/flank.apt"),
    seed!("fuzz/seeds/toolpath/cl.csv"),
    seed!("examples/chip/joints_no_rtcp.csv"),
];
const GRIND_TABLES: &[&[u8]] = &[
    seed!("examples/grind/probe.csv"),
    seed!("examples/grind/edge.csv"),
];
const NC_PROGRAMS: &[&[u8]] = &[
    seed!("examples/grind/flute.nc"),
    seed!("crates/runout-io/tests/data/fuzz_nc_many_decimals.nc"),
];
const PEAK_TABLES: &[&[u8]] = &[
    seed!("examples/seed003_table1.csv"),
    seed!("examples/seed003_table1.toml"),
];
const DISPLACEMENT: &[&[u8]] = &[
    seed!("fuzz/seeds/displacement/teeth.csv"),
    seed!("fuzz/seeds/displacement/teeth_seed_edges.csv"),
    seed!("fuzz/seeds/displacement/heights.csv"),
    seed!("fuzz/seeds/displacement/heights_runout.csv"),
    seed!("fuzz/seeds/displacement/signal.csv"),
    seed!("fuzz/seeds/displacement/signal_encoder.csv"),
];
const FRF: &[&[u8]] = &[
    seed!("fuzz/seeds/frf/frf.csv"),
    seed!("fuzz/seeds/frf/frf_semicolon.txt"),
];

/// A position as a fraction of a length (`u32::MAX` + 1 = the whole length).
#[derive(Debug, Clone, Copy)]
struct Index(u32);

impl Index {
    /// The position in `0..size` (`size` > 0).
    fn index(self, size: usize) -> usize {
        ((u64::from(self.0) * size as u64) >> 32) as usize
    }

    /// `k` of `size`, for the tests of the mutations.
    fn of(k: usize, size: usize) -> Index {
        Index((((k as u64) << 32) / size as u64 + 1) as u32)
    }
}

fn index() -> impl Strategy<Value = Index> {
    any::<u32>().prop_map(Index)
}

/// One change to the bytes; positions are fractions of the current length.
#[derive(Debug, Clone)]
enum Mutation {
    FlipBit(Index, u8),
    Insert(Index, u8),
    Delete(Index, u8),
    Truncate(Index),
    /// Head of this example up to the first index, tail of another from the second.
    Splice(Index, Index, Index),
    DuplicateLine(Index),
}

/// Bytes that matter to the formats, inserted more often than random ones.
const STRUCTURAL: &[u8] = b",;\t\n\r#=[]\"'.-+eE0 9:/()_xXGNaA%\x00\xff";

fn mutation(n_examples: usize) -> impl Strategy<Value = Mutation> {
    let byte = prop_oneof![any::<u8>(), proptest::sample::select(STRUCTURAL)];
    prop_oneof![
        3 => (index(), 0u8..8).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        3 => (index(), byte).prop_map(|(i, b)| Mutation::Insert(i, b)),
        3 => (index(), 1u8..12).prop_map(|(i, n)| Mutation::Delete(i, n)),
        1 => index().prop_map(Mutation::Truncate),
        1 => (index(), index(), index())
            .prop_filter("two examples", move |_| n_examples > 0)
            .prop_map(|(e, a, b)| Mutation::Splice(e, a, b)),
        1 => index().prop_map(Mutation::DuplicateLine),
    ]
}

fn apply(examples: &[&[u8]], base: usize, ops: &[Mutation]) -> Vec<u8> {
    let mut v = examples[base].to_vec();
    let at = |i: &Index, len: usize| i.index(len + 1);
    for op in ops {
        match op {
            Mutation::FlipBit(i, b) if !v.is_empty() => {
                let k = i.index(v.len());
                v[k] ^= 1 << b;
            }
            Mutation::FlipBit(..) => {}
            Mutation::Insert(i, b) => {
                let k = at(i, v.len());
                v.insert(k, *b);
            }
            Mutation::Delete(i, n) => {
                let k = at(i, v.len());
                let end = (k + *n as usize).min(v.len());
                v.drain(k..end);
            }
            Mutation::Truncate(i) => {
                let k = at(i, v.len());
                v.truncate(k);
            }
            Mutation::Splice(e, a, b) => {
                let other = examples[e.index(examples.len())];
                let k = at(a, v.len());
                v.truncate(k);
                v.extend_from_slice(&other[b.index(other.len() + 1)..]);
            }
            Mutation::DuplicateLine(i) => {
                let lines: Vec<&[u8]> = v.split_inclusive(|&c| c == b'\n').collect();
                if !lines.is_empty() {
                    let k = i.index(lines.len());
                    let mut out = Vec::with_capacity(v.len() + lines[k].len());
                    for (j, l) in lines.iter().enumerate() {
                        out.extend_from_slice(l);
                        if j == k {
                            out.extend_from_slice(l);
                        }
                    }
                    v = out;
                }
            }
        }
    }
    v
}

/// Mutated bytes of one of `examples` (1 to 4 mutations).
fn mutated(examples: &'static [&'static [u8]]) -> impl Strategy<Value = Vec<u8>> {
    (
        0..examples.len(),
        proptest::collection::vec(mutation(examples.len()), 1..5),
    )
        .prop_map(move |(base, ops)| apply(examples, base, &ops))
}

/// `cases` per parser, times `MUTATED_INPUTS_FACTOR` (default 1) for a longer search:
/// `MUTATED_INPUTS_FACTOR=50 cargo test --release -p runout-io --test io mutated_inputs::`.
fn config(cases: u32) -> ProptestConfig {
    let factor: u32 = std::env::var("MUTATED_INPUTS_FACTOR")
        .ok()
        .and_then(|f| f.parse().ok())
        .unwrap_or(1);
    ProptestConfig {
        cases: cases.saturating_mul(factor.max(1)),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// The line an error message gives right after the file name (`file:12:`, `file:12:3:` or
/// `file, line 12:`), if any.
fn line_after(msg: &str, file: &str) -> Option<usize> {
    let rest = &msg[msg.find(file)? + file.len()..];
    let rest = rest
        .strip_prefix(':')
        .or_else(|| rest.strip_prefix(", line "))?;
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// An error about `text` read as `file`: names the file, gives a line that exists (if any), is
/// one bounded message (quotes are cut at 80 characters), and has no doubled cause.
fn check_file_error(msg: &str, file: &str, text: &[u8]) -> Result<(), TestCaseError> {
    prop_assert!(msg.contains(file), "error does not name `{file}`: {msg}");
    let lines = text.split(|&b| b == b'\n').count().max(1);
    if let Some(l) = line_after(msg, file) {
        prop_assert!(
            (1..=lines + 1).contains(&l),
            "line {l} of a {lines}-line file: {msg}"
        );
    }
    check_bounded(msg)
}

fn check_bounded(msg: &str) -> Result<(), TestCaseError> {
    prop_assert!(!msg.trim().is_empty());
    prop_assert!(msg.chars().count() < 1200, "message too long: {msg}");
    Ok(())
}

fn text(bytes: &[u8]) -> Option<&str> {
    std::str::from_utf8(bytes).ok()
}

/// The error of a whole-file parser that takes the text (not the path): as `check_file_error`.
fn check<T, E: std::fmt::Display>(
    r: Result<T, E>,
    file: &str,
    bytes: &[u8],
) -> Result<Option<T>, TestCaseError> {
    match r {
        Ok(v) => Ok(Some(v)),
        Err(e) => {
            check_file_error(&e.to_string(), file, bytes)?;
            Ok(None)
        }
    }
}

proptest! {
    #![proptest_config(config(8192))]

    #[test]
    fn recordings(bytes in mutated(RECORDINGS)) {
        for (file, opts) in [
            ("rec.txt", ReadOptions::default()),
            ("rec.csv", ReadOptions::new().sample_rate_hz(1000.0)),
        ] {
            if let Some(r) = check(Recording::from_bytes(file, &bytes, &opts), file, &bytes)? {
                prop_assert!(r.time_s.iter().all(|t| t.is_finite()));
                prop_assert!(r.time_s.windows(2).all(|w| w[1] > w[0]), "time not increasing");
            }
        }
    }

    #[test]
    fn axis_mappings(bytes in mutated(AXES)) {
        if let Some(t) = text(&bytes) {
            if let Err(e) = AxisMapping::parse(t) {
                let m = e.to_string();
                prop_assert!(m.starts_with("axis mapping `"), "{m}");
                check_bounded(&m)?;
            }
        }
    }

    #[test]
    fn quantities(bytes in mutated(QUANTITIES)) {
        if let Some(t) = text(&bytes) {
            for q in [Quantity::LengthMm, Quantity::LengthUm, Quantity::AngleDeg,
                      Quantity::SpeedRpm, Quantity::TimeS, Quantity::Dimensionless] {
                match parse_quantity(t, q) {
                    Ok(v) => prop_assert!(v.is_finite(), "{t:?} → {v}"),
                    Err(e) => {
                        let m = e.to_string();
                        // names the offending text (cut to 80 characters) and what was expected
                        prop_assert!(m.starts_with('`') && m.contains("expected")
                            || m.contains("unit"), "{m}");
                        check_bounded(&m)?;
                    }
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(config(4096))]

    #[test]
    fn simulate_and_identify_configs(bytes in mutated(CONFIGS)) {
        let Some(t) = text(&bytes) else { return Ok(()) };
        if let Some(l) = check(layer_from_toml("case.toml", t, &simulate_key_names()), "case.toml", &bytes)? {
            let mut s = Settings::new();
            s.push(l);
            if let Err(e) = resolve_simulate(&s) {
                let m = e.to_string();
                // a key of the file, or a missing key with the flag that gives it
                prop_assert!(m.contains("case.toml") || m.contains("missing `"), "{m}");
                check_bounded(&m)?;
            }
        }
        if let Some(l) = check(layer_from_toml("cut.toml", t, &identify_key_names()), "cut.toml", &bytes)? {
            let mut s = Settings::new();
            s.push(l);
            if let Err(e) = resolve_identify(&s, 2) {
                let m = e.to_string();
                prop_assert!(m.contains("cut.toml") || m.contains("missing `") || m.contains("--"), "{m}");
                check_bounded(&m)?;
            }
        }
    }

    #[test]
    fn shank_configs(bytes in mutated(SHANK_CONFIGS)) {
        if let Some(t) = text(&bytes) {
            check(ShankConfig::parse("shank.toml", t), "shank.toml", &bytes)?;
        }
    }

    #[test]
    fn chip_cases(bytes in mutated(CHIP_CASES)) {
        let Some(t) = text(&bytes) else { return Ok(()) };
        let (case, path) = t.split_once("\n@@@\n").unwrap_or((t, ""));
        if let Some(specs) = check(parse_case_specs("case.toml", case), "case.toml", case.as_bytes())? {
            let dir = tempfile::tempdir().unwrap();
            for name in ["flank.apt", "joints.csv", "tp.csv"] {
                std::fs::write(dir.path().join(name), path).unwrap();
            }
            for s in specs.into_iter().take(3) {
                if let Err(e) = resolve_case("case.toml", dir.path(), s) {
                    let m = e.to_string();
                    prop_assert!(m.contains("case.toml") || m.contains(".apt") || m.contains(".csv"), "{m}");
                    check_bounded(&m)?;
                }
            }
        }
    }

    #[test]
    fn toolpaths(bytes in mutated(TOOLPATHS)) {
        let Some(t) = text(&bytes) else { return Ok(()) };
        for (file, parsed) in [("f.apt", parse_apt("f.apt", t)), ("f.csv", parse_cl_csv("f.csv", t))] {
            if let Some(mut tp) = check(parsed, file, &bytes)? {
                if let Some(cl) = check(tp.cl_points(file, Some(600.0)), file, &bytes)? {
                    prop_assert!(cl.iter().all(|p| p.feed.is_finite() && p.feed > 0.0 && p.p.norm().is_finite()));
                }
            }
        }
        if let Some(blocks) = check(parse_joint_csv("j.csv", t), "j.csv", &bytes)? {
            check(joint_points("j.csv", &blocks, Some(600.0)), "j.csv", &bytes)?;
        }
    }

    #[test]
    fn grind_tables(bytes in mutated(GRIND_TABLES)) {
        let Some(t) = text(&bytes) else { return Ok(()) };
        check(read_probe_csv(t, "probe.csv"), "probe.csv", &bytes)?;
        check(read_edge_csv(t, "edge.csv"), "edge.csv", &bytes)?;
    }

    #[test]
    fn nc_programs(bytes in mutated(NC_PROGRAMS)) {
        let Some(t) = text(&bytes) else { return Ok(()) };
        // the lexer ends a line at `\n`, `\r\n` or a lone `\r` (old controls)
        let lines = t.replace("\r\n", "\n").split(['\n', '\r']).count();
        let located = |e: &runout_io::gcode::NcError| -> Result<(), TestCaseError> {
            prop_assert!((1..=lines + 1).contains(&e.line) && e.column >= 1, "{e}");
            prop_assert!(e.to_string().starts_with("line "), "{e}");
            check_bounded(&e.to_string())
        };
        if let Err(e) = lex(t) {
            located(&e)?;
        }
        match NcProgram::parse(t) {
            Err(e) => located(&e)?,
            Ok(p) => {
                // no offsets: the program comes back byte for byte
                let none = vec![None; p.motion_blocks().len()];
                prop_assert_eq!(p.rewrite(&none, &RewriteOptions::default()).unwrap(), t);
                let some = vec![Some([0.001, -0.002, 0.0]); p.motion_blocks().len()];
                if let Err(e) = p.rewrite(&some, &RewriteOptions::default()) {
                    located(&e)?;
                }
            }
        }
    }

    #[test]
    fn peak_tables(bytes in mutated(PEAK_TABLES)) {
        let Some(t) = text(&bytes) else { return Ok(()) };
        for (file, r) in [("t.csv", peak_table::parse_csv("t.csv", t)), ("t.toml", peak_table::parse_toml("t.toml", t))] {
            if let Some(table) = check(r, file, &bytes)? {
                // the sign (peaks are magnitudes) is checked by `ToothPeaks::new`, with the row named by the CLI
                prop_assert!(table.rows.iter().all(|r| r.peaks_n.iter().all(|p| p.is_finite())));
            }
        }
    }

    #[test]
    fn frf_tables(bytes in mutated(FRF)) {
        let Some(t) = text(&bytes) else { return Ok(()) };
        if let Some(chain) = check(parse_frf("frf.csv", t), "frf.csv", &bytes)? {
            for f in [0.0, 50.0, 1e3] {
                if let Some(h) = chain.x.response(f) {
                    prop_assert!(h.re.is_finite() && h.im.is_finite());
                }
            }
        }
    }
}

proptest! {
    // each case writes a file: fewer cases
    #![proptest_config(config(2048))]

    #[test]
    fn displacement_tables(bytes in mutated(DISPLACEMENT)) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("table.csv");
        std::fs::write(&path, &bytes).unwrap();
        let file = path.display().to_string();
        if let Some(t) = check(read_tooth_table(&path, 4), &file, &bytes)? {
            prop_assert!(t.readings.iter().all(|(k, v)| *k < 4 && v.is_finite()));
        }
        if let Some(rows) = check(read_height_table(&path), &file, &bytes)? {
            prop_assert!(rows.iter().all(|r| r.runout_mm >= 0.0 && r.z_mm.is_finite()));
        }
        if let Some(s) = check(read_signal(&path, &SignalSection::default()), &file, &bytes)? {
            prop_assert!(s.sample_rate_hz.is_finite() && s.sample_rate_hz > 0.0);
        }
        let section = SignalSection { from_s: Some(0.001), to_s: Some(0.005), max_samples: 30 };
        if let Some(s) = check(read_signal(&path, &section), &file, &bytes)? {
            prop_assert!(s.channels.iter().all(|c| c.1.len() <= 30));
        }
    }
}

/// The mutations themselves: each kind changes what it should (a test of the test).
#[test]
fn mutations_do_what_they_say() {
    let ex: &[&[u8]] = &[b"ab\ncd\n", b"XY"];
    let i = Index::of;
    assert_eq!(apply(ex, 0, &[Mutation::Truncate(i(2, 7))]), b"ab");
    assert_eq!(apply(ex, 0, &[Mutation::FlipBit(i(0, 6), 0)]), b"`b\ncd\n");
    assert_eq!(apply(ex, 0, &[Mutation::Delete(i(0, 7), 3)]), b"cd\n");
    assert_eq!(
        apply(ex, 0, &[Mutation::DuplicateLine(i(0, 2))]),
        b"ab\nab\ncd\n"
    );
    assert_eq!(
        apply(ex, 0, &[Mutation::Splice(i(1, 2), i(3, 7), i(1, 3))]),
        b"ab\nY"
    );
}

/// Two long recordings (past the 1 000 rows read ahead at open, so that the data rows go
/// through the parallel parser): comma-separated with a time column, and semicolon-separated
/// with decimal commas; values in the formats exports use (signs, exponents, long mantissas).
fn long_recordings() -> &'static [&'static [u8]] {
    static LONG: std::sync::OnceLock<Vec<&'static [u8]>> = std::sync::OnceLock::new();
    LONG.get_or_init(|| {
        let cell = |i: usize, k: usize| -> String {
            let x = ((i * 7919 + k * 104_729) % 20_011) as f64 / 97.0 - 100.0;
            match (i + k) % 4 {
                0 => format!("{x}"),
                1 => format!("{x:.3}"),
                2 => format!("{:e}", x * 1e-3),
                _ => format!("{}", x.round() as i64),
            }
        };
        let mut comma = String::from("time_s,Fx,Fy,Fz\n");
        let mut semi = String::from("Zeit [s];Fx [N];Fy [N]\n");
        for i in 0..2_500 {
            let t = i as f64 * 1e-4;
            comma += &format!("{t},{},{},{}\n", cell(i, 0), cell(i, 1), cell(i, 2));
            let row = format!("{t};{};{}\n", cell(i, 3), cell(i, 4));
            semi += &row.replace('.', ",");
        }
        vec![
            Box::leak(comma.into_bytes().into_boxed_slice()) as &[u8],
            Box::leak(semi.into_bytes().into_boxed_slice()) as &[u8],
        ]
    })
}

/// Chunks (as bits), the error message, bytes read and warnings of a reader's data rows.
type Reading = (
    Vec<(u64, Vec<u64>, Vec<Vec<u64>>)>,
    Option<String>,
    u64,
    Vec<String>,
);

fn bits(c: &runout_io::recording::RecordingChunk) -> (u64, Vec<u64>, Vec<Vec<u64>>) {
    let b = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    (
        c.first_sample,
        b(&c.time_s),
        c.values.iter().map(|v| b(v)).collect(),
    )
}

/// `bytes` read with `read_chunk` in a loop (`workers` = 0) or parsed on `workers` threads in
/// jobs of about `job_bytes` bytes; `None` when the header is refused (the same either way).
fn reading(bytes: &[u8], rows: usize, workers: usize, job_bytes: usize) -> Option<Reading> {
    use runout_io::recording::{RecordingChunk, RecordingReader};
    let opts = ReadOptions::new().sample_rate_hz(10_000.0);
    let mut r = RecordingReader::from_reader(std::io::Cursor::new(bytes), "rec.csv", &opts).ok()?;
    let mut c = RecordingChunk::default();
    let mut out = Vec::new();
    let error = if workers == 0 {
        loop {
            match r.read_chunk(&mut c, rows) {
                Ok(0) => break None,
                Ok(_) => out.push(bits(&c)),
                Err(e) => break Some(e.to_string()),
            }
        }
    } else {
        r.for_each_chunk_in_jobs_of(job_bytes, &mut c, rows, workers, |c, _, _| {
            out.push(bits(c));
            true
        })
        .err()
        .map(|e| e.to_string())
    };
    Some((out, error, r.bytes_read(), r.warnings().to_vec()))
}

proptest! {
    #![proptest_config(config(256))]

    /// The parallel parser of `identify`'s pass 1 on mutated long recordings, cut into small
    /// jobs so that many job seams fall anywhere in the data: the same chunks (bit for bit),
    /// the same first error (message, line, column), the same bytes read and warnings as
    /// `read_chunk` in a loop.
    #[test]
    fn recordings_parse_the_same_on_several_threads(
        bytes in mutated(long_recordings()),
        rows in prop_oneof![Just(1usize), 1..5_000usize],
        workers in 2..4usize,
        job_bytes in prop_oneof![1..64usize, 64..20_000usize],
    ) {
        // bytes read after an error: `read_chunk` counts the failing line, the parallel parser
        // the jobs before it (progress only: the job stops at the error either way)
        let ignore_bytes_after_error = |r: Option<Reading>| {
            r.map(|(c, e, b, w)| { let b = if e.is_some() { 0 } else { b }; (c, e, b, w) })
        };
        let serial = ignore_bytes_after_error(reading(&bytes, rows, 0, 0));
        let parallel = ignore_bytes_after_error(reading(&bytes, rows, workers, job_bytes));
        prop_assert!(serial == parallel, "rows {rows}, {workers} workers, jobs of {job_bytes} B: {:?} / {:?}",
            serial.as_ref().map(|s| (s.0.len(), &s.1, s.2)), parallel.as_ref().map(|s| (s.0.len(), &s.1, s.2)));
    }
}

/// The long recordings themselves read without error past the read-ahead (so the property
/// above is not vacuous), the same on several threads in jobs of a few rows.
#[test]
fn long_recordings_read_whole_on_several_threads() {
    for bytes in long_recordings() {
        let serial = reading(bytes, 700, 0, 0).expect("header accepted");
        assert_eq!(serial.1, None, "no error");
        let rows: usize = serial.0.iter().map(|c| c.1.len()).sum();
        assert_eq!(rows, 2_500);
        assert_eq!(Some(&serial), reading(bytes, 700, 3, 100).as_ref());
    }
}
