//! Unit/quantity parser, config layers (simulate and identify keys) resolved into model types,
//! and peak tables.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::config::identify::{identify_key_names, resolve_identify};
use runout_io::config::simulate::{resolve_simulate, simulate_key_names};
use runout_io::config::{layer_from_toml, Settings};
use runout_io::peak_table::{parse_csv, parse_toml};
use runout_io::units::{parse_quantity, Quantity};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for q in [
        Quantity::LengthMm,
        Quantity::LengthUm,
        Quantity::AngleDeg,
        Quantity::SpeedRpm,
        Quantity::TimeS,
        Quantity::Dimensionless,
    ] {
        if let Ok(v) = parse_quantity(text, q) {
            assert!(v.is_finite());
        }
    }
    if let Ok(l) = layer_from_toml("case.toml", text, &simulate_key_names()) {
        let mut s = Settings::new();
        s.push(l);
        let _ = resolve_simulate(&s);
    }
    if let Ok(l) = layer_from_toml("cut.toml", text, &identify_key_names()) {
        let mut s = Settings::new();
        s.push(l);
        let _ = resolve_identify(&s, 2);
    }
    let _ = parse_toml("t.toml", text);
    let _ = parse_csv("t.csv", text);
});
