//! Displacement tables (`runout displacement`): per-tooth readings (then the joint fit), runout at
//! several heights (then the scalar and vector fits), and the raw signal (whole file and a time
//! section). The readers take a path: the input is written to one file in a temporary folder.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_core::displacement::{
    identify_from_teeth, runout_at_height, vector_at_height, HeightRegression, SensorSign,
    ToothFitOptions, ToothReadings,
};
use runout_core::Cutter;
use runout_io::displacement::{read_height_table, read_signal, read_tooth_table, SignalSection};
use std::path::PathBuf;
use std::sync::OnceLock;

fn scratch() -> &'static (tempfile::TempDir, PathBuf) {
    static DIR: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("table.csv");
        (d, p)
    })
}

fuzz_target!(|data: &[u8]| {
    let path = &scratch().1;
    std::fs::write(path, data).unwrap();
    for teeth in [3usize, 4] {
        if let Ok(t) = read_tooth_table(path, teeth) {
            assert!(t.readings.iter().all(|(k, v)| *k < teeth && v.is_finite()));
            if let Ok(r) = ToothReadings::new(teeth, &t.readings, SensorSign::Radial) {
                let cutter = Cutter::flat(10.0, teeth, 30.0f64.to_radians()).unwrap();
                let _ = identify_from_teeth(&r, &ToothFitOptions::new(cutter));
            }
        }
    }
    if let Ok(rows) = read_height_table(path) {
        let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.z_mm, r.runout_mm)).collect();
        for m in [HeightRegression::Ols, HeightRegression::SeedEq6] {
            let _ = runout_at_height(&pts, 0.0, m);
        }
        let v: Option<Vec<(f64, [f64; 2])>> = rows
            .iter()
            .map(|r| {
                r.angle_rad
                    .map(|l| (r.z_mm, [r.runout_mm * l.cos(), r.runout_mm * l.sin()]))
            })
            .collect();
        if let Some(v) = v {
            let _ = vector_at_height(&v, 0.0);
        }
    }
    if let Ok(s) = read_signal(path, &SignalSection::default()) {
        assert!(s.sample_rate_hz.is_finite() && s.sample_rate_hz > 0.0);
        assert!(s.channels.iter().all(|c| c.1.len() >= 2));
    }
    let section = SignalSection {
        from_s: Some(0.001),
        to_s: Some(0.01),
        max_samples: 50,
    };
    if let Ok(s) = read_signal(path, &section) {
        assert!(s.channels.iter().all(|c| c.1.len() <= 50));
    }
});
