//! The library examples run: examples/shank_force.rs finds what it simulated, and
//! examples/identify.rs (the README's main job) gives the numbers of the CLI's JSON.

#[path = "../examples/shank_force.rs"]
#[allow(dead_code)]
mod example;

#[path = "../examples/identify.rs"]
#[allow(dead_code)]
mod identify_example;

/// The JSON body of the CLI snapshot `name` (crates/runout-cli/tests/cli/snapshots).
fn cli_json(name: &str) -> serde_json::Value {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../runout-cli/tests/cli/snapshots")
        .join(format!("cli__snapshots__{name}.snap"));
    let text = std::fs::read_to_string(&p).unwrap();
    let rest = text.strip_prefix("---").unwrap();
    serde_json::from_str(&rest[rest.find("\n---\n").unwrap() + 5..]).unwrap()
}

/// Every test of this binary runs on a global rayon pool of one thread, as the CLI snapshots
/// (`RAYON_NUM_THREADS=1`), whichever test starts first. (Not `ThreadPool::install`: a fit
/// called from inside a pool splits its parallel sums differently from one called from
/// outside, as the CLI's main thread does, and the last digits differ.)
fn one_thread() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build_global()
            .expect("the first rayon use of this test binary");
    });
}

/// The example built its request from plain values (no config file, no CLI); with one rayon
/// thread, as the snapshot was made (the full-signal fit's disk sums are then in a fixed
/// order), every number equals the CLI's `runout identify … --config cut.toml --json -` to
/// the last digit. Only the file names differ (absolute here, relative in the snapshot).
#[test]
fn identify_example_gives_the_cli_numbers() {
    one_thread();
    let r = identify_example::run().unwrap();
    let mut lib: serde_json::Value = serde_json::from_str(&runout::to_json(&r).unwrap()).unwrap();
    let mut cli = cli_json("identify_recordings");
    for v in [&mut lib, &mut cli] {
        for rec in v["recordings"].as_array_mut().unwrap() {
            rec["file"] = "-".into();
        }
        for rec in v["consistency"]["recordings"].as_array_mut().unwrap() {
            rec["file"] = "-".into();
        }
        for rec in v["answer"]["cross_checks"].as_array_mut().unwrap() {
            rec["file"] = "-".into();
        }
        // assumed defaults are stated by the config resolver (the CLI), not for plain values
        v["answer"]["warnings"]
            .as_array_mut()
            .unwrap()
            .retain(|w| !w.as_str().unwrap_or("").starts_with("assumed"));
    }
    assert_eq!(lib, cli);
    // what the example prints: ρ, λ and the six coefficients (ρ = 8 µm at −50° simulated)
    let f = r.full_signal.ok().unwrap();
    assert!((f.offset_um - 8.0).abs() < 0.2, "{}", f.offset_um);
    assert!((f.angle_deg + 50.0).abs() < 1.0, "{}", f.angle_deg);
    assert_eq!(f.coefficients.all().len(), 6);
}

#[test]
fn shank_force_example_recovers_the_runout() {
    one_thread();
    let r = example::run().unwrap();
    assert_eq!(r.schema, "runout.shank.force/2");
    assert_eq!(r.recording, "synthetic.csv");
    // 10 µm at the tip, no tilt (noise-free, 5-decimal µm CSV)
    assert!(
        (r.runout.tip_offset_um - 10.0).abs() < 0.05,
        "{:?}",
        r.runout
    );
    assert!(r.runout.tilt_um_per_mm < 0.01, "{:?}", r.runout);
    assert_eq!(r.force_over_cut.len(), 2);
    assert!(r.force_over_cut.iter().all(|f| f.rms_N > 1.0));
    // the report serialises to the JSON the CLI writes
    let j: serde_json::Value = serde_json::from_str(&runout::to_json(&r).unwrap()).unwrap();
    assert_eq!(j["runout"]["tip_offset_um"], r.runout.tip_offset_um);
}

/// Progress: two stages (the two passes) over the whole input, each begun and ended once.
#[test]
fn shank_force_reports_progress_per_pass() {
    one_thread();
    #[derive(Default)]
    struct Log(Vec<String>, u64, u64);
    impl runout::Progress for Log {
        fn begin(&mut self, stage: &str, total: Option<u64>) {
            self.0.push(format!("begin {stage}"));
            self.1 = total.unwrap_or(0);
            self.2 = 0;
        }
        fn set_position(&mut self, bytes: u64) {
            assert!(bytes >= self.2 && bytes <= self.1, "{bytes} of {}", self.1);
            self.2 = bytes;
        }
        fn advance(&mut self, bytes: u64) {
            self.2 += bytes;
            assert!(self.2 <= self.1, "{} of {}", self.2, self.1);
        }
        fn end(&mut self) {
            self.0.push(format!(
                "end at {}",
                if self.2 == self.1 { "total" } else { "less" }
            ));
        }
    }
    let req = example::request().unwrap();
    let mut log = Log::default();
    let a = runout::shank::force(&req, &mut log).unwrap();
    assert_eq!(
        log.0,
        [
            "begin pass 1/2",
            "end at total",
            "begin pass 2/2",
            "end at total"
        ]
    );
    // the progress sink does not change the result
    let b = example::run().unwrap();
    assert_eq!(runout::to_json(&a).unwrap(), runout::to_json(&b).unwrap());
}

/// Sources in memory give the report of the files (only the names differ), and progress comes
/// as one stage per recording, named by it, begun and ended once.
#[test]
fn identify_reads_bytes_like_files_and_reports_progress() {
    one_thread();
    #[derive(Default)]
    struct Log(Vec<String>);
    impl runout::Progress for Log {
        fn begin(&mut self, stage: &str, _total: Option<u64>) {
            self.0.push(format!("begin {stage}"));
        }
        fn end(&mut self) {
            self.0.push("end".into());
        }
    }
    let from_files = identify_example::run().unwrap();
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/identify");
    let mut req = runout::identify::RecordingsRequest::new(
        Vec::new(),
        runout::core::Cutter::flat(10.0, 4, 30f64.to_radians()).unwrap(),
        Vec::new(),
    );
    for fz in [0.05, 0.08] {
        let name = format!("cut_fz{fz}.txt");
        let bytes = std::fs::read(format!("{dir}/{name}")).unwrap();
        req.recordings.push(runout::Source::bytes(name, bytes));
        req.cuts.push(
            runout::core::Cut::new(3240.0, fz, 2.0)
                .unwrap()
                .radial(2.0, runout::core::MillingMode::Down, &req.cutter)
                .unwrap(),
        );
    }
    let mut log = Log::default();
    let from_bytes = runout::identify::recordings(&req, &mut log).unwrap();
    assert_eq!(
        log.0,
        ["begin cut_fz0.05.txt", "end", "begin cut_fz0.08.txt", "end"]
    );
    assert_eq!(from_bytes.recordings[1].file, "cut_fz0.08.txt");
    let json = |r: &runout::identify::RecordingsReport| {
        let mut v: serde_json::Value = serde_json::from_str(&runout::to_json(r).unwrap()).unwrap();
        for rec in v["recordings"].as_array_mut().unwrap() {
            rec["file"] = "-".into();
        }
        for rec in v["consistency"]["recordings"].as_array_mut().unwrap() {
            rec["file"] = "-".into();
        }
        for rec in v["answer"]["cross_checks"].as_array_mut().unwrap() {
            rec["file"] = "-".into();
        }
        // assumed defaults are stated by the config resolver (the CLI), not for plain values
        v["answer"]["warnings"]
            .as_array_mut()
            .unwrap()
            .retain(|w| !w.as_str().unwrap_or("").starts_with("assumed"));
        v
    };
    assert_eq!(json(&from_files), json(&from_bytes));
}
