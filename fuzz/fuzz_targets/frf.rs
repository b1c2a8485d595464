//! Measured FRF tables (`frf = "…"` in shank configs, `--sensor-frf` of `identify`): parsed into a
//! measuring chain, then evaluated and applied to a short periodic waveform and a series.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::frf::parse_frf;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(chain) = parse_frf("frf.csv", text) else {
        return;
    };
    let wave: Vec<f64> = (0..16).map(|i| (i as f64 * 0.4).sin()).collect();
    for axis in [&chain.x, &chain.y, &chain.z] {
        for f in [0.0, 1.0, 100.0, 1e4, 1e9] {
            if let Some(h) = axis.response(f) {
                assert!(h.re.is_finite() && h.im.is_finite(), "{h} at {f} Hz");
            }
        }
        let _ = axis.apply_periodic(&wave, 50.0, Some(16.0));
        let _ = axis.filter(1000.0, &wave);
    }
});
