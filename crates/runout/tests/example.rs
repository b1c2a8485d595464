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
