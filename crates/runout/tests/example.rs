//! The library example (examples/shank_force.rs) runs and finds what it simulated.

#[path = "../examples/shank_force.rs"]
#[allow(dead_code)]
mod example;

#[test]
fn shank_force_example_recovers_the_runout() {
    let r = example::run().unwrap();
    assert_eq!(r.schema, "runout.shank.force/1");
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
