//! Recording readers (DynoWare text export, CSV/TSV) and the axis mapping.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::recording::{AxisMapping, ReadOptions, Recording};

fuzz_target!(|data: &[u8]| {
    let _ = Recording::from_bytes("rec.txt", data, &ReadOptions::default());
    let _ = Recording::from_bytes("rec.csv", data, &ReadOptions::new().sample_rate_hz(1000.0));
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = AxisMapping::parse(text);
    }
});
