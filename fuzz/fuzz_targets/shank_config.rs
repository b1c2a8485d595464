//! The shank TOML config and its air-cut windows in the streaming survey.
#![no_main]
use libfuzzer_sys::fuzz_target;
use runout_io::config::shank::ShankConfig;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = ShankConfig::parse("shank.toml", text);
});
